// The chains of a procedural character: their shapes (points or arcs), physics, view examples and mirrored copies.
#include "scene/character_loader.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <kodawari/rods/world.hpp>

namespace kodawari::scene_detail {

using Vec3 = glm::vec3;

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
    rods::default_orientations(shape);
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
        rods::default_orientations(shape);
        return shape;
    }
    const std::string quat_what = "an array of " + std::to_string(n) + " unit quaternions [x, y, z, w], one per position";
    std::size_t m = 0;
    KW_SCENE_ASSIGN(m, read_array(r, orientations, n, n, quat_what));
    shape.orientations.resize(m);
    for (std::size_t i = 0; i < m; ++i) KW_SCENE_ASSIGN(shape.orientations[i], read_unit_quat(r, r.element(orientations, i)));
    return shape;
}

Result<glm::quat> read_unit_quat(const JsonReader& r, const JsonNode& q) {
    constexpr std::string_view kQuat = "a unit quaternion [x, y, z, w] (length within 1e-3 of 1)";
    std::size_t four = 0;
    KW_SCENE_ASSIGN(four, r.array(q, kQuat));
    if (four != 4) return r.expected(q, kQuat);
    std::array<float, 4> c{};
    for (std::size_t k = 0; k < 4; ++k) KW_SCENE_ASSIGN(c[k], r.real(r.element(q, k), NumberRange::closed(-2.0, 2.0)));
    const glm::quat value(c[3], c[0], c[1], c[2]);
    if (!(std::abs(glm::length(value) - 1.0f) < 1e-3f)) return r.expected(q, kQuat);
    return glm::normalize(value);
}

Result<void> read_physics(const JsonReader& r, const JsonNode& node, rods::SolverParams& p) {
    KW_TRY(r.object(node, {"stiffness", "rest_stiffness", "damping", "normal_drag", "tangent_drag", "iterations", "max_substep",
                           "gravity", "wind", "momentum_suppression", "start", "teleport_distance"}));
    KW_TRY(optional_member(r, node, "stiffness", p.stiffness,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1.0)); }));
    KW_TRY(optional_member(r, node, "rest_stiffness", p.rest_stiffness,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1.0)); }));
    KW_TRY(optional_member(r, node, "damping", p.damping,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1000.0)); }));
    KW_TRY(optional_member(r, node, "normal_drag", p.normal_drag,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1000.0)); }));
    KW_TRY(optional_member(r, node, "tangent_drag", p.tangent_drag,
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
    if (const JsonNode start = r.member(node, "start"); start.present()) {
        std::string value;
        KW_SCENE_ASSIGN(value, r.string(start));
        if (value != "settled" && value != "rest") return r.fail(start.path, "expected \"settled\" or \"rest\", got \"" + value + "\"");
        p.settle_start = value == "settled";
    }
    KW_TRY(optional_member(r, node, "teleport_distance", p.teleport_distance,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1e6)); }));
    return {};
}

Result<void> read_wind(const JsonReader& r, const JsonNode& node, rods::WindField& w) {
    KW_TRY(r.object(node, {"velocity", "gust", "gust_period", "gust_size", "seed"}));
    KW_TRY(optional_member(r, node, "velocity", w.velocity, [&](const JsonNode& n) { return read_point(r, n, 100.0); }));
    KW_TRY(optional_member(r, node, "gust", w.gust, [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 4.0)); }));
    KW_TRY(optional_member(r, node, "gust_period", w.gust_period,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.05, 1000.0)); }));
    KW_TRY(optional_member(r, node, "gust_size", w.gust_size,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.05, 10000.0)); }));
    if (const JsonNode seed = r.member(node, "seed"); seed.present()) {
        std::uint64_t value = 0;
        KW_SCENE_ASSIGN(value, r.integer(seed, 0, 0xFFFFFFFFu));
        w.seed = static_cast<std::uint32_t>(value);
    }
    return {};
}

// `replaces`: the example a sketch replaced (kodawari/scene/scene_edit.hpp), kept so that
// `sketch --undo` can bring it back. It is checked as a view of the same chain (so an
// undo never writes what the loader refuses) and otherwise unused; it nests when a sketch
// replaces a sketch, at most kMaxReplacedDepth deep.
constexpr int kMaxReplacedDepth = 16;

Result<ViewSpec> read_view_at(const JsonReader& r, const JsonNode& node, std::size_t joints, int depth) {
    KW_TRY(r.object(node, {"name", "direction", "influence", "shape", "replaces"}));
    if (const JsonNode replaced = r.member(node, "replaces"); replaced.present()) {
        if (depth >= kMaxReplacedDepth) {
            return r.fail(replaced.path, "expected at most " + std::to_string(kMaxReplacedDepth) + " nested replaced examples");
        }
        KW_TRY(read_view_at(r, replaced, joints, depth + 1));
    }
    ViewSpec v;
    KW_TRY(optional_member(r, node, "name", v.name, [&](const JsonNode& n) { return r.string(n); }));
    KW_SCENE_ASSIGN(v.view.direction, read_direction(r, r.member(node, "direction")));
    KW_TRY(optional_member(r, node, "influence", v.view.influence,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, rods::kMaxInfluence)); }));
    KW_SCENE_ASSIGN(v.shape, read_shape(r, r.member(node, "shape"), joints));
    return v;
}

Result<ViewSpec> read_view(const JsonReader& r, const JsonNode& node, std::size_t joints) {
    return read_view_at(r, node, joints, 0);
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

Result<rods::ChainTemplate> make_template(const std::string& name, const ChainSpec& chain) {
    std::vector<rods::ChainShape> shapes;
    std::vector<rods::ViewExample> views;
    for (const ViewSpec& v : chain.views) {
        shapes.push_back(v.shape);
        views.push_back(v.view);
    }
    auto t = rods::make_chain_template(name, chain.base, shapes, views, chain.thickness, chain.mass, chain.params);
    if (t && !chain.limits.empty()) KW_TRY(rods::set_limits(t.value().chain, chain.limits, name + ".limit"));
    if (!t || chain.keyed.empty()) return t;
    std::vector<rods::KeySourceKind> sources;
    for (const rods::KeyJoint& k : chain.key_sources) sources.push_back(k.kind);
    std::vector<rods::ChainShape> keyed_shapes;
    std::vector<rods::KeyedExample> keyed;
    for (const KeyedSpec& k : chain.keyed) {
        keyed_shapes.push_back(k.shape);
        keyed.push_back(k.example);
    }
    KW_TRY(rods::add_keyed_examples(t.value(), sources, keyed_shapes, keyed));
    return t;
}

Result<void> check_template(const JsonReader& r, const JsonNode& node, const ChainSpec& chain) {
    auto t = make_template(chain.name, chain);
    if (!t) return r.fail(node.path, t.error().message);
    return {};
}

// The solver's bounds (rods/solver.hpp) as decimals that messages print as written; any
// double in them converts to a float in the solver's.
static_assert(static_cast<float>(1e-5) == rods::kMinThickness && static_cast<float>(1.0) == rods::kMaxThickness);
static_assert(static_cast<float>(1e-9) == rods::kMinMass && static_cast<float>(1000.0) == rods::kMaxMass);

std::vector<std::string> collider_names(const std::vector<ColliderSpec>& colliders) {
    std::vector<std::string> out;
    for (const ColliderSpec& c : colliders) out.push_back(c.name);
    return out;
}

namespace {

// A chain's `colliders` (VRM's per-spring collider groups): names of its character's
// colliders, each once; without the list, all of them, which one chain can take only up
// to rods::kMaxChainColliders.
Result<void> read_chain_colliders(const JsonReader& r, const JsonNode& node, const JointLookup& joints, ChainSpec& c) {
    const JsonNode list = r.member(node, "colliders");
    const std::size_t total = joints.colliders.size();
    if (!list.present()) {
        if (c.collide && total > rods::kMaxChainColliders) {
            return r.fail(node.path, "collides with all " + std::to_string(total) + " colliders of its character, and one "
                                     "chain may touch at most " + std::to_string(rods::kMaxChainColliders) +
                                     "; give it a \"colliders\" list of collider names");
        }
        return {};
    }
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, list, 0, rods::kMaxChainColliders,
                                  "an array of at most " + std::to_string(rods::kMaxChainColliders) + " collider names"));
    std::vector<std::string> named;
    for (const std::string& name : joints.colliders) {
        if (!name.empty()) named.push_back(name);
    }
    c.all_colliders = false;
    for (std::size_t k = 0; k < n; ++k) {
        const JsonNode entry = r.element(list, k);
        std::string name;
        KW_SCENE_ASSIGN(name, r.string(entry));
        const auto it = std::find(joints.colliders.begin(), joints.colliders.end(), name);
        if (name.empty() || it == joints.colliders.end()) {
            return r.expected(entry, named.empty() ? std::string("the name of a collider (this character's colliders have no names)")
                                                   : "the name of a collider of this character: " + quoted_list(named));
        }
        const auto index = static_cast<std::uint32_t>(it - joints.colliders.begin());
        if (std::find(c.colliders.begin(), c.colliders.end(), index) != c.colliders.end()) {
            return r.expected(entry, "a collider not listed before (\"" + name + "\" is)");
        }
        c.colliders.push_back(index);
    }
    return {};
}

}  // namespace

// One joint's limit, as VRMC_springBone_limit's `limit` object with the scene format's
// units: exactly one of {"cone": {"angle_deg", "rotation"}}, {"hinge": {"angle_deg",
// "rotation"}}, {"spherical": {"pitch_deg", "yaw_deg", "rotation"}}; `rotation` as
// elsewhere ({"axis", "angle_deg"}), the identity when absent (docs/scene-format.md).
Result<rods::AngleLimit> read_limit(const JsonReader& r, const JsonNode& node) {
    KW_TRY(r.object(node, {"cone", "hinge", "spherical"}));
    const JsonNode kinds[3] = {r.member(node, "cone"), r.member(node, "hinge"), r.member(node, "spherical")};
    const int given = int(kinds[0].present()) + int(kinds[1].present()) + int(kinds[2].present());
    if (given != 1) return r.expected(node, "exactly one of \"cone\", \"hinge\" or \"spherical\"");
    rods::AngleLimit limit;
    const NumberRange half_turn = NumberRange::closed(0.0, 180.0);
    if (kinds[2].present()) {
        const JsonNode& k = kinds[2];
        KW_TRY(r.object(k, {"pitch_deg", "yaw_deg", "rotation"}));
        limit.kind = rods::LimitKind::Spherical;
        KW_SCENE_ASSIGN(limit.angle, read_degrees(r, r.member(k, "pitch_deg"), half_turn));
        KW_SCENE_ASSIGN(limit.yaw, read_degrees(r, r.member(k, "yaw_deg"), NumberRange::closed(0.0, 90.0)));
    } else {
        const JsonNode& k = kinds[0].present() ? kinds[0] : kinds[1];
        KW_TRY(r.object(k, {"angle_deg", "rotation"}));
        limit.kind = kinds[0].present() ? rods::LimitKind::Cone : rods::LimitKind::Hinge;
        KW_SCENE_ASSIGN(limit.angle, read_degrees(r, r.member(k, "angle_deg"), half_turn));
    }
    const JsonNode& k = kinds[0].present() ? kinds[0] : kinds[1].present() ? kinds[1] : kinds[2];
    KW_TRY(optional_member(r, k, "rotation", limit.rotation, [&](const JsonNode& n) { return read_rotation(r, n); }));
    // Degrees to radians rounds 180 and 90 to a hair above pi and pi/2 in float.
    limit.angle = std::min(limit.angle, rods::kMaxLimitAngle);
    limit.yaw = std::min(limit.yaw, rods::kMaxLimitYaw);
    return limit;
}

// `limit`: one limit object for every segment, or an array of one per segment (joint i
// to i+1: joint count - 1 entries), null where a joint has none.
Result<void> read_limits(const JsonReader& r, const JsonNode& node, ChainSpec& c) {
    const JsonNode limit = r.member(node, "limit");
    if (!limit.present()) return {};
    const std::size_t segments = c.base.positions.size() - 1;
    if (!limit.value->is_array()) {
        rods::AngleLimit one;
        KW_SCENE_ASSIGN(one, read_limit(r, limit));
        c.limits.assign(segments, one);
        return {};
    }
    const std::string what = "an array of " + std::to_string(segments) +
                             " limits, one per segment of the chain (null where a joint has none)";
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, limit, segments, segments, what));
    c.limits.assign(segments, rods::AngleLimit{});
    for (std::size_t i = 0; i < n; ++i) {
        const JsonNode e = r.element(limit, i);
        if (e.value->is_null()) continue;
        KW_SCENE_ASSIGN(c.limits[i], read_limit(r, e));
    }
    return {};
}

Result<void> read_chain_settings(const JsonReader& r, const JsonNode& node, const JointLookup& joints, ChainSpec& c) {
    KW_TRY(optional_member(r, node, "thickness", c.thickness,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(1e-5, 1.0)); }));
    KW_TRY(optional_member(r, node, "mass", c.mass,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(1e-9, 1000.0)); }));
    const JsonNode physics = r.member(node, "physics");
    if (physics.present()) KW_TRY(read_physics(r, physics, c.params));
    KW_TRY(optional_member(r, node, "collide", c.collide, [&](const JsonNode& n) { return r.boolean(n); }));
    KW_TRY(read_chain_colliders(r, node, joints, c));
    const JsonNode center = r.member(node, "center");
    if (center.present()) {
        std::uint32_t joint = 0;
        KW_SCENE_ASSIGN(joint, joints.find(center));
        c.center = static_cast<std::int32_t>(joint);
    }
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
    const JsonNode keyed = r.member(node, "keyed");
    if (keyed.present()) KW_TRY(read_keyed(r, keyed, joints, c));
    KW_TRY(read_limits(r, node, c));
    KW_TRY(check_template(r, node, c));
    // A particle thicker than half its segment overlaps its neighbours' spheres, and a
    // collider's push of one then moves the next by more than the segment allows (the
    // issue measured 1 887% stretch at a 1 m thickness); the solver keeps lengths, so
    // such a chain jitters against its colliders instead of lying on them.
    float shortest = std::numeric_limits<float>::infinity();
    for (std::size_t i = 0; i + 1 < c.base.positions.size(); ++i) {
        shortest = std::min(shortest, glm::length(c.base.positions[i + 1] - c.base.positions[i]));
    }
    if (c.thickness > 0.5f * shortest) {
        const JsonNode given = r.member(node, "thickness");
        return r.fail(given.present() ? given.path : node.path,
                      "thickness " + std::to_string(c.thickness) + " m is more than half the chain's shortest segment (" +
                          std::to_string(shortest) + " m); at most " + std::to_string(0.5f * shortest) + " m");
    }
    return {};
}

Result<void> read_chain(const JsonReader& r, const JsonNode& node, const rods::Skeleton& skeleton,
                        const std::vector<ColliderSpec>& colliders, const rods::SolverParams& defaults,
                        std::vector<ChainSpec>& chains) {
    KW_TRY(r.object(node, {"name", "joint", "offset", "shape", "thickness", "mass", "physics", "collide", "colliders",
                           "center", "mirror", "views", "keyed", "limit"}));
    ChainSpec c;
    c.path = node.path;
    c.params = defaults;
    const JsonNode name = r.member(node, "name");
    KW_SCENE_ASSIGN(c.name, read_name(r, name));
    KW_SCENE_ASSIGN(c.joint, find_joint(r, r.member(node, "joint"), skeleton));
    KW_TRY(optional_member(r, node, "offset", c.offset, [&](const JsonNode& n) { return read_transform(r, n); }));
    KW_SCENE_ASSIGN(c.base, read_shape(r, r.member(node, "shape"), 0));
    JointLookup joints;
    joints.find = [&](const JsonNode& n) { return find_joint(r, n, skeleton); };
    joints.parent = [&](std::uint32_t j) { return skeleton.joints[j].parent; };
    // A procedural joint's rotation relative to its parent is its local one (pose_skeleton).
    joints.rest_rotation = [&](std::uint32_t j) { return skeleton.joints[j].rest.rotation; };
    joints.reference = skeleton.reference;
    joints.colliders = collider_names(colliders);
    KW_TRY(read_chain_settings(r, node, joints, c));

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
    // The mirror chain's keys are the mirror images too: a head turn to the left keys the
    // left strand as a turn to the right keys the right one. Magnitudes do not change.
    for (KeyedSpec& k : m.keyed) {
        k.shape = mirror(k.shape);
        if (k.example.kind == rods::KeyKind::Motion && k.example.frame == rods::MotionFrame::Joint) {
            // A velocity is a vector, an angular velocity a pseudovector (mirrored: -M w).
            k.example.value = k.example.measure == rods::MotionMeasure::AngularSpeed ? -mirror(k.example.value)
                                                                                     : mirror(k.example.value);
        }
        for (glm::quat& q : k.example.rotations) q = mirror(q);
    }
    // A limit's frame is its joint's, mirrored with it (M R M); cones, hinges about X
    // and spherical limits are symmetric under x -> -x in their own frames.
    for (rods::AngleLimit& l : m.limits) l.rotation = mirror(l.rotation);
    chains.push_back(std::move(m));
    return {};
}

}  // namespace kodawari::scene_detail
