// The version-2 scene keys (docs/scene-format.md, "Characters", "Crowds", "Moving
// camera"): every value is checked here, with its JSON path, so that a scene that loads
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

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kMaxCoordinate = 1e6;  // world positions (m), as the bird loader
constexpr double kMaxLocal = 1000.0;    // offsets inside a character (m)
constexpr double kMaxShape = 100.0;     // chain shape coordinates (m)
constexpr double kMaxTime = 1e5;        // motion times (s)

constexpr std::size_t kMaxCameraKeys = 4096;

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

// The default orientations of a shape (docs: each joint's local +Y along its segment,
// the last joint along the last segment, by the shortest arc from +Y), as in the rod
// tests' shape_from.
void default_orientations(rods::ChainShape& shape) {
    const std::size_t n = shape.positions.size();
    shape.orientations.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t seg = std::min(i, n - 2);
        const Vec3 dir = glm::normalize(shape.positions[seg + 1] - shape.positions[seg]);
        shape.orientations[i] = rods::shortest_arc(Vec3(0.0f, 1.0f, 0.0f), dir);
    }
}

// {"arc": {...}}: a strand on a circular arc of arc length `length` that leaves the root
// tangent to `direction` and turns by `curl_deg` in all about `bend_axis`. Joint i sits
// on the circle; segment i points along the tangent at its middle, (i + 1/2) steps of
// curl / (joints - 1) from `direction`, and every segment is length / (joints - 1) long.
Result<rods::ChainShape> read_arc(const JsonReader& r, const JsonNode& node) {
    KW_TRY(r.object(node, {"joints", "length", "direction", "bend_axis", "curl_deg"}));
    std::uint64_t joints = 0;
    KW_SCENE_ASSIGN(joints, r.integer(r.member(node, "joints"), 2, rods::kMaxChainJoints));
    float length = 0.0f;
    KW_SCENE_ASSIGN(length, r.real(r.member(node, "length"), NumberRange::left_open(0.0, kMaxShape)));
    Vec3 direction(0.0f, 1.0f, 0.0f);
    Vec3 axis(0.0f, 0.0f, 1.0f);
    KW_TRY(optional_member(r, node, "direction", direction, [&](const JsonNode& n) { return read_direction(r, n); }));
    KW_TRY(optional_member(r, node, "bend_axis", axis, [&](const JsonNode& n) { return read_direction(r, n); }));
    float curl = 0.0f;
    KW_TRY(optional_member(r, node, "curl_deg", curl,
                           [&](const JsonNode& n) { return read_degrees(r, n, NumberRange::closed(-1080.0, 1080.0)); }));
    if (curl != 0.0f && glm::length(glm::cross(direction, axis)) < 1e-3f) {
        return r.expected(r.member(node, "bend_axis"), "a vector not parallel to \"direction\" (the arc bends about it)");
    }
    const auto segments = static_cast<float>(joints - 1);
    const float step = curl / segments;
    rods::ChainShape shape;
    shape.positions.push_back(Vec3(0.0f));
    for (std::uint64_t i = 0; i + 1 < joints; ++i) {
        const Vec3 dir = glm::angleAxis((static_cast<float>(i) + 0.5f) * step, axis) * direction;
        shape.positions.push_back(shape.positions.back() + (length / segments) * glm::normalize(dir));
    }
    default_orientations(shape);
    return shape;
}

// A shape: {"positions": [...], "orientations": [...]} or {"arc": {...}}. `joints` is
// the required joint count (0: any in 2..32, for a base shape).
Result<rods::ChainShape> read_shape(const JsonReader& r, const JsonNode& node, std::size_t joints) {
    KW_TRY(r.object(node, {"positions", "orientations", "arc"}));
    const JsonNode positions = r.member(node, "positions");
    const JsonNode orientations = r.member(node, "orientations");
    const JsonNode arc = r.member(node, "arc");
    if (positions.present() == arc.present()) {
        return r.fail(node.path, std::string("expected exactly one of \"positions\" and \"arc\", got ") +
                                     (arc.present() ? "both" : "neither"));
    }
    const std::string count_what =
        joints == 0 ? "2 to " + std::to_string(rods::kMaxChainJoints) + " joints"
                    : std::to_string(joints) + " joints (as many as the chain's base shape)";
    rods::ChainShape shape;
    if (arc.present()) {
        if (orientations.present()) return r.fail(orientations.path, "not used with \"arc\" (an arc makes its own orientations)");
        KW_SCENE_ASSIGN(shape, read_arc(r, arc));
        if (joints != 0 && shape.positions.size() != joints) {
            return r.expected(r.member(arc, "joints"), count_what);
        }
        return shape;
    }
    const std::string what =
        "an array of " +
        (joints == 0 ? "2 to " + std::to_string(rods::kMaxChainJoints) + " joint positions"
                     : std::to_string(joints) + " joint positions (as many as the chain's base shape)") +
        " [x, y, z], the first [0, 0, 0]";
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, positions, joints == 0 ? 2 : joints, joints == 0 ? rods::kMaxChainJoints : joints, what));
    shape.positions.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const JsonNode p = r.element(positions, i);
        KW_SCENE_ASSIGN(shape.positions[i], read_point(r, p, kMaxShape));
        if (i == 0 && shape.positions[0] != Vec3(0.0f)) {
            return r.expected(p, "[0, 0, 0] (joint 0 sits at the chain root; move the chain with \"offset\")");
        }
        // rods::make_basis's limit: a shorter segment has no direction.
        if (i > 0 && !(glm::length(shape.positions[i] - shape.positions[i - 1]) >= 1e-6f)) {
            return r.expected(p, "a point at least 1e-6 m from the previous joint");
        }
    }
    if (!orientations.present()) {
        default_orientations(shape);
        return shape;
    }
    const std::string quat_what = "an array of " + std::to_string(n) + " unit quaternions [x, y, z, w], one per position";
    std::size_t m = 0;
    KW_SCENE_ASSIGN(m, read_array(r, orientations, n, n, quat_what));
    shape.orientations.resize(m);
    for (std::size_t i = 0; i < m; ++i) {
        const JsonNode q = r.element(orientations, i);
        constexpr std::string_view kQuat = "a unit quaternion [x, y, z, w] (length within 1e-3 of 1)";
        std::size_t four = 0;
        KW_SCENE_ASSIGN(four, r.array(q, kQuat));
        if (four != 4) return r.expected(q, kQuat);
        std::array<float, 4> c{};
        for (std::size_t k = 0; k < 4; ++k) KW_SCENE_ASSIGN(c[k], r.real(r.element(q, k), NumberRange::closed(-2.0, 2.0)));
        const glm::quat value(c[3], c[0], c[1], c[2]);
        if (!(std::abs(glm::length(value) - 1.0f) < 1e-3f)) return r.expected(q, kQuat);
        shape.orientations[i] = glm::normalize(value);
    }
    return shape;
}

Result<void> read_physics(const JsonReader& r, const JsonNode& node, rods::SolverParams& p) {
    KW_TRY(r.object(node, {"stiffness", "rest_stiffness", "damping", "iterations", "max_substep", "gravity", "wind",
                           "momentum_suppression"}));
    KW_TRY(optional_member(r, node, "stiffness", p.stiffness,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1.0)); }));
    KW_TRY(optional_member(r, node, "rest_stiffness", p.rest_stiffness,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1.0)); }));
    KW_TRY(optional_member(r, node, "damping", p.damping,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1000.0)); }));
    const JsonNode iterations = r.member(node, "iterations");
    if (iterations.present()) {
        std::uint64_t value = 0;
        KW_SCENE_ASSIGN(value, r.integer(iterations, 1, 64));
        p.iterations = static_cast<std::uint32_t>(value);
    }
    KW_TRY(optional_member(r, node, "max_substep", p.max_substep,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 0.05)); }));
    const auto accel = [&](const JsonNode& n) { return read_point(r, n, 1000.0); };
    KW_TRY(optional_member(r, node, "gravity", p.gravity, accel));
    KW_TRY(optional_member(r, node, "wind", p.wind, accel));
    KW_TRY(optional_member(r, node, "momentum_suppression", p.momentum_suppression,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1.0)); }));
    return {};
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

// A sphere or capsule on the joint whose index `joint` returns for the `joint` member.
Result<ColliderSpec> read_collider(const JsonReader& r, const JsonNode& node,
                                  const std::function<Result<std::uint32_t>(const JsonNode&)>& joint) {
    if (!node.present() || !node.value->is_object()) {
        return r.expected(node, "an object with \"type\": \"sphere\" or \"capsule\"");
    }
    std::size_t type = 0;
    KW_SCENE_ASSIGN(type, r.choice(r.member(node, "type"), {"sphere", "capsule"}));
    ColliderSpec c;
    KW_SCENE_ASSIGN(c.joint, joint(r.member(node, "joint")));
    if (type == 0) {
        KW_TRY(r.object(node, {"type", "joint", "center", "radius"}));
        KW_TRY(optional_member(r, node, "center", c.a, [&](const JsonNode& n) { return read_point(r, n, kMaxLocal); }));
        c.b = c.a;
    } else {
        KW_TRY(r.object(node, {"type", "joint", "a", "b", "radius"}));
        KW_SCENE_ASSIGN(c.a, read_point(r, r.member(node, "a"), kMaxLocal));
        KW_SCENE_ASSIGN(c.b, read_point(r, r.member(node, "b"), kMaxLocal));
    }
    KW_SCENE_ASSIGN(c.radius, r.real(r.member(node, "radius"), NumberRange::left_open(0.0, kMaxLocal)));
    return c;
}

}  // namespace

Result<std::vector<ColliderSpec>> read_colliders(const JsonReader& r, const JsonNode& node,
                                                 const std::function<Result<std::uint32_t>(const JsonNode&)>& joint) {
    std::vector<ColliderSpec> out;
    const JsonNode colliders = r.member(node, "colliders");
    if (!colliders.present()) return out;
    // Every colliding chain of the character touches all of them, and one chain may touch
    // at most rods::kMaxChainColliders (the GPU keeps them in fixed arrays).
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, colliders, 0, rods::kMaxChainColliders,
                                  "an array of colliders (at most " + std::to_string(rods::kMaxChainColliders) + ")"));
    for (std::size_t i = 0; i < n; ++i) {
        ColliderSpec c;
        KW_SCENE_ASSIGN(c, read_collider(r, r.element(colliders, i), joint));
        out.push_back(c);
    }
    return out;
}

Result<ViewSpec> read_view(const JsonReader& r, const JsonNode& node, std::size_t joints) {
    KW_TRY(r.object(node, {"name", "direction", "influence", "shape"}));
    ViewSpec v;
    KW_TRY(optional_member(r, node, "name", v.name, [&](const JsonNode& n) { return r.string(n); }));
    KW_SCENE_ASSIGN(v.view.direction, read_direction(r, r.member(node, "direction")));
    KW_TRY(optional_member(r, node, "influence", v.view.influence,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1000.0)); }));
    KW_SCENE_ASSIGN(v.shape, read_shape(r, r.member(node, "shape"), joints));
    return v;
}

// The mirror image of a chain across the X = 0 plane of its joint's frame (and of the
// reference joint's frame for the view directions): x -> -x for points and directions,
// and for a rotation M R M (M = diag(-1, 1, 1)), which is the quaternion (w, x, -y, -z).
glm::quat mirror(glm::quat q) { return glm::quat(q.w, q.x, -q.y, -q.z); }
Vec3 mirror(Vec3 v) { return Vec3(-v.x, v.y, v.z); }
rods::ChainShape mirror(const rods::ChainShape& s) {
    rods::ChainShape out = s;
    for (Vec3& p : out.positions) p = mirror(p);
    for (glm::quat& q : out.orientations) q = mirror(q);
    return out;
}

Result<void> check_template(const JsonReader& r, const JsonNode& node, const ChainSpec& chain) {
    std::vector<rods::ChainShape> shapes;
    std::vector<rods::ViewExample> views;
    for (const ViewSpec& v : chain.views) {
        shapes.push_back(v.shape);
        views.push_back(v.view);
    }
    auto t = rods::make_chain_template(chain.name, chain.base, shapes, views, chain.thickness, chain.mass, chain.params);
    if (!t) return r.fail(node.path, t.error().message);
    return {};
}

Result<void> read_chain_settings(const JsonReader& r, const JsonNode& node, ChainSpec& c) {
    KW_TRY(optional_member(r, node, "thickness", c.thickness,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1.0)); }));
    KW_TRY(optional_member(r, node, "mass", c.mass, [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1000.0)); }));
    const JsonNode physics = r.member(node, "physics");
    if (physics.present()) KW_TRY(read_physics(r, physics, c.params));
    KW_TRY(optional_member(r, node, "collide", c.collide, [&](const JsonNode& n) { return r.boolean(n); }));
    const JsonNode views = r.member(node, "views");
    if (views.present()) {
        const std::string what = "an array of at most " + std::to_string(rods::kMaxViewExamples) + " view examples";
        std::size_t n = 0;
        KW_SCENE_ASSIGN(n, read_array(r, views, 0, rods::kMaxViewExamples, what));
        for (std::size_t k = 0; k < n; ++k) {
            ViewSpec v;
            KW_SCENE_ASSIGN(v, read_view(r, r.element(views, k), c.base.positions.size()));
            c.views.push_back(std::move(v));
        }
    }
    KW_TRY(check_template(r, node, c));
    return {};
}

Result<void> read_chain(const JsonReader& r, const JsonNode& node, const rods::Skeleton& skeleton,
                        const rods::SolverParams& defaults, std::vector<ChainSpec>& chains) {
    KW_TRY(r.object(node, {"name", "joint", "offset", "shape", "thickness", "mass", "physics", "collide", "mirror", "views"}));
    ChainSpec c;
    c.path = node.path;
    c.params = defaults;
    const JsonNode name = r.member(node, "name");
    KW_SCENE_ASSIGN(c.name, read_name(r, name));
    KW_SCENE_ASSIGN(c.joint, find_joint(r, r.member(node, "joint"), skeleton));
    KW_TRY(optional_member(r, node, "offset", c.offset, [&](const JsonNode& n) { return read_transform(r, n); }));
    KW_SCENE_ASSIGN(c.base, read_shape(r, r.member(node, "shape"), 0));
    KW_TRY(read_chain_settings(r, node, c));

    const auto unique = [&](const JsonNode& at, const std::string& candidate) -> Result<void> {
        for (const ChainSpec& other : chains) {
            if (other.name == candidate) {
                return r.expected(at, "a chain name this character does not use yet (\"" + candidate + "\" is taken)");
            }
        }
        return {};
    };
    KW_TRY(unique(name, c.name));
    const JsonNode mirror_node = r.member(node, "mirror");
    std::string mirror_name;
    KW_TRY(optional_member(r, node, "mirror", mirror_name, [&](const JsonNode& n) { return read_name(r, n); }));
    chains.push_back(c);
    if (mirror_name.empty()) return {};
    if (mirror_name == c.name) return r.expected(mirror_node, "a name other than the chain's own");
    KW_TRY(unique(mirror_node, mirror_name));
    ChainSpec m = std::move(c);
    m.name = mirror_name;
    m.path = mirror_node.path;
    m.offset.position = mirror(m.offset.position);
    m.offset.rotation = mirror(m.offset.rotation);
    m.base = mirror(m.base);
    for (ViewSpec& v : m.views) {
        v.view.direction = mirror(v.view.direction);
        v.shape = mirror(v.shape);
    }
    chains.push_back(std::move(m));
    return {};
}

Result<CharacterSpec> read_character(const JsonReader& r, const JsonNode& node) {
    if (node.present() && node.value->is_object() && r.member(node, "gltf").present()) return read_rigged_character(r, node);
    KW_TRY(r.object(node, {"name", "skeleton", "reference_joint", "motions", "colliders", "physics", "chains"}));
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
    for (std::size_t i = 0; i < n; ++i) KW_TRY(read_chain(r, r.element(chains, i), ch.skeleton, defaults, ch.chains));
    if (ch.chains.size() > kMaxPerCharacter) {
        return r.expected(chains, chains_what + ", counting mirrored copies; got " + std::to_string(ch.chains.size()));
    }
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

Result<std::size_t> read_interpolation(const JsonReader& r, const JsonNode& node, rods::Interpolation& out) {
    std::size_t value = 0;
    KW_SCENE_ASSIGN(value, r.choice(node, {"catmull-rom", "linear"}));
    out = value == 0 ? rods::Interpolation::CatmullRom : rods::Interpolation::Linear;
    return value;
}

Result<void> read_orbit(const JsonReader& r, const JsonNode& node, rods::CameraMotion& m) {
    KW_TRY(r.object(node, {"target", "radius", "height", "degrees_per_second", "period", "start_deg"}));
    m.kind = rods::CameraMotion::Kind::Orbit;
    KW_SCENE_ASSIGN(m.target, read_point(r, r.member(node, "target"), kMaxCoordinate / 2));
    KW_SCENE_ASSIGN(m.radius, r.real(r.member(node, "radius"), NumberRange::left_open(0.0, kMaxCoordinate / 2)));
    KW_TRY(optional_member(r, node, "height", m.height,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(-kMaxCoordinate / 2, kMaxCoordinate / 2)); }));
    const JsonNode rate = r.member(node, "degrees_per_second");
    const JsonNode period = r.member(node, "period");
    if (rate.present() && period.present()) {
        return r.fail(period.path, "expected at most one of \"degrees_per_second\" and \"period\", got both");
    }
    m.rate = static_cast<float>(30.0 * kDegToRad);
    if (rate.present()) KW_SCENE_ASSIGN(m.rate, read_degrees(r, rate, NumberRange::closed(-36000.0, 36000.0)));
    if (period.present()) {
        double seconds = 0.0;
        KW_SCENE_ASSIGN(seconds, r.number(period, NumberRange::left_open(0.0, kMaxTime)));
        m.rate = static_cast<float>(2.0 * std::numbers::pi / seconds);
    }
    KW_TRY(optional_member(r, node, "start_deg", m.start_angle,
                           [&](const JsonNode& n) { return read_degrees(r, n, NumberRange::closed(-3600.0, 3600.0)); }));
    return {};
}

Result<void> read_path(const JsonReader& r, const JsonNode& node, rods::CameraMotion& m) {
    KW_TRY(r.object(node, {"points", "target", "segment_duration", "interpolation", "loop"}));
    m.kind = rods::CameraMotion::Kind::Keyframes;
    Vec3 target{};
    KW_SCENE_ASSIGN(target, read_point(r, r.member(node, "target"), kMaxCoordinate));
    float segment = 1.0f;
    KW_TRY(optional_member(r, node, "segment_duration", segment,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 3600.0)); }));
    const JsonNode interpolation = r.member(node, "interpolation");
    if (interpolation.present()) KW_TRY(read_interpolation(r, interpolation, m.interpolation));
    KW_TRY(optional_member(r, node, "loop", m.loop, [&](const JsonNode& n) { return r.boolean(n); }));
    const JsonNode points = r.member(node, "points");
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, points, 2, kMaxCameraKeys - 1,
                                  "an array of 2 to " + std::to_string(kMaxCameraKeys - 1) + " points [x, y, z]"));
    for (std::size_t i = 0; i < n; ++i) {
        const JsonNode p = r.element(points, i);
        rods::CameraKey key;
        KW_SCENE_ASSIGN(key.position, read_point(r, p, kMaxCoordinate));
        if (key.position == target) return r.expected(p, "a point other than the path's target (the camera needs a direction)");
        key.time = static_cast<float>(static_cast<double>(segment) * static_cast<double>(i));
        key.target = target;
        m.keys.push_back(key);
    }
    if (m.loop) {
        rods::CameraKey close = m.keys.front();
        close.time = static_cast<float>(static_cast<double>(segment) * static_cast<double>(n));
        m.keys.push_back(close);
    }
    return {};
}

Result<void> read_keyframes(const JsonReader& r, const JsonNode& node, rods::CameraMotion& m) {
    KW_TRY(r.object(node, {"keys", "interpolation", "loop"}));
    m.kind = rods::CameraMotion::Kind::Keyframes;
    const JsonNode interpolation = r.member(node, "interpolation");
    if (interpolation.present()) KW_TRY(read_interpolation(r, interpolation, m.interpolation));
    KW_TRY(optional_member(r, node, "loop", m.loop, [&](const JsonNode& n) { return r.boolean(n); }));
    const JsonNode keys = r.member(node, "keys");
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, keys, m.loop ? 2 : 1, kMaxCameraKeys,
                                  "an array of " + std::string(m.loop ? "2" : "1") + " to " + std::to_string(kMaxCameraKeys) +
                                      " keys {\"time\", \"position\", \"target\"}"));
    for (std::size_t i = 0; i < n; ++i) {
        const JsonNode k = r.element(keys, i);
        KW_TRY(r.object(k, {"time", "position", "target"}));
        rods::CameraKey key;
        const JsonNode time = r.member(k, "time");
        KW_SCENE_ASSIGN(key.time, read_time(r, time));
        if (i > 0 && !(key.time > m.keys.back().time)) {
            return r.expected(time, "a time after the previous key's (" + format_number(m.keys.back().time) + " s)");
        }
        KW_SCENE_ASSIGN(key.position, read_point(r, r.member(k, "position"), kMaxCoordinate));
        KW_SCENE_ASSIGN(key.target, read_point(r, r.member(k, "target"), kMaxCoordinate));
        if (key.target == key.position) {
            return r.expected(r.member(k, "target"), "a point other than the key's position (the camera needs a direction)");
        }
        m.keys.push_back(key);
    }
    if (m.loop && (m.keys.back().position != m.keys.front().position || m.keys.back().target != m.keys.front().target)) {
        return r.expected(r.element(keys, n - 1), "the same position and target as keys[0] (a looping camera ends where it starts)");
    }
    return {};
}


Result<void> read_camera_motion(const JsonReader& r, const JsonNode& node, CameraSpec& camera) {
    rods::CameraMotion& m = camera.motion;
    m.kind = rods::CameraMotion::Kind::Fixed;
    m.position = to_vec(camera.position);
    m.target = to_vec(camera.target);
    const JsonNode projection = r.member(node, "projection");
    if (projection.present()) {
        std::size_t value = 0;
        KW_SCENE_ASSIGN(value, r.choice(projection, {"perspective", "orthographic"}));
        m.projection = value == 0 ? rods::Camera::Projection::Perspective : rods::Camera::Projection::Orthographic;
    }
    const char* moving = nullptr;
    for (const char* key : {"orbit", "path", "keyframes"}) {
        const JsonNode n = r.member(node, key);
        if (!n.present()) continue;
        if (moving != nullptr) {
            return r.fail(n.path, std::string("expected at most one of \"orbit\", \"path\" and \"keyframes\", got \"") + moving +
                                      "\" and \"" + key + "\"");
        }
        moving = key;
    }
    if (moving == nullptr) return {};
    for (const char* fixed : {"position", "target"}) {
        const JsonNode n = r.member(node, fixed);
        if (n.present()) {
            return r.fail(n.path, std::string("not used with \"") + moving + "\" (it places and aims the camera itself)");
        }
    }
    const JsonNode n = r.member(node, moving);
    if (std::string_view(moving) == "orbit") return read_orbit(r, n, m);
    if (std::string_view(moving) == "path") return read_path(r, n, m);
    return read_keyframes(r, n, m);
}

Result<void> read_characters(const JsonReader& r, const JsonNode& characters, const JsonNode& crowds, Scene& scene) {
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, characters, 1, 1024, "a non-empty array of characters (at most 1024)"));
    for (std::size_t i = 0; i < n; ++i) {
        const JsonNode node = r.element(characters, i);
        CharacterSpec c;
        KW_SCENE_ASSIGN(c, read_character(r, node));
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
