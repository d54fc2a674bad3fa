// The VRM spring-bone reader's colliders (vrm_reader.hpp): VRMC_springBone 1.0's colliders
// and their shapes, with VRMC_springBone_extended_collider 1.0's shapes in place of the
// base ones where given. VRM 0.x's collider groups are read with its springs (vrm.cpp).

#include <cmath>
#include <string>

#include "gltf/vrm_reader.hpp"

namespace kodawari::gltf::vrm_detail {

// A collider shape object {sphere: {...}}, {capsule: {...}} (VRM 1.0 and extended) or,
// in the extended collider only, {plane: {offset, normal}}. `inside` is read only
// from the extended collider (VRMC_springBone_extended_collider 1.0's shapes).
Result<bool> Reader::shape(const json& shape_obj, const std::string& path, VrmCollider& out, bool extended) {
    if (const auto it = shape_obj.find("sphere"); it != shape_obj.end() && it->is_object()) {
        const std::string p = path + ".sphere";
        auto offset = vec3(*it, "offset", p, glm::vec3(0.0f));
        auto r = radius(*it, p, 0.0f);
        if (!offset) return offset.error();
        if (!r) return r.error();
        out.capsule = false;
        out.offset = out.tail = offset.value();
        out.radius = r.value();
        auto inside = flag(*it, "inside", p, extended);
        if (!inside) return inside.error();
        out.kind = inside.value() ? rods::ColliderKind::Inside : rods::ColliderKind::Outside;
        return true;
    }
    if (const auto it = shape_obj.find("capsule"); it != shape_obj.end() && it->is_object()) {
        const std::string p = path + ".capsule";
        auto offset = vec3(*it, "offset", p, glm::vec3(0.0f));
        auto tail = vec3(*it, "tail", p, glm::vec3(0.0f));
        auto r = radius(*it, p, 0.0f);
        if (!offset) return offset.error();
        if (!tail) return tail.error();
        if (!r) return r.error();
        out.capsule = true;
        out.offset = offset.value();
        out.tail = tail.value();
        out.radius = r.value();
        auto inside = flag(*it, "inside", p, extended);
        if (!inside) return inside.error();
        out.kind = inside.value() ? rods::ColliderKind::Inside : rods::ColliderKind::Outside;
        return true;
    }
    if (const auto it = shape_obj.find("plane"); extended && it != shape_obj.end() && it->is_object()) {
        const std::string p = path + ".plane";
        auto offset = vec3(*it, "offset", p, glm::vec3(0.0f));
        auto normal = vec3(*it, "normal", p, glm::vec3(0.0f, 0.0f, 1.0f));  // the extension's default
        if (!offset) return offset.error();
        if (!normal) return normal.error();
        const float length = glm::length(normal.value());
        if (!(length > 1e-6f)) {
            return invalid(p + ".normal", "a plane's normal must be a non-zero vector (got [" + std::to_string(normal.value().x) +
                                              ", " + std::to_string(normal.value().y) + ", " + std::to_string(normal.value().z) + "])");
        }
        out.capsule = false;
        out.kind = rods::ColliderKind::Plane;
        out.offset = offset.value();
        out.normal = normal.value() / length;
        out.tail = out.offset + out.normal;
        out.radius = 0.0f;
        return true;
    }
    return false;
}

// An optional boolean member, read only when `read` (else false).
Result<bool> Reader::flag(const json& parent, const std::string& key, const std::string& path, bool read) {
    if (!read) return false;
    const auto it = parent.find(key);
    if (it == parent.end()) return false;
    if (!it->is_boolean()) return invalid(path + "." + key, "expected true or false");
    return it->get<bool>();
}

Result<void> Reader::read_collider_1(const json& collider, const std::string& path) {
    if (!collider.is_object()) return invalid(path, "expected an object");
    auto node = index(collider, "node", path, c_.nodes.size(), "node");
    if (!node) return node.error();
    VrmCollider out;
    out.node = static_cast<int>(node.value());
    auto base = object(collider, "shape", path, true);
    if (!base) return base.error();
    auto mapped = shape(*base.value(), path + ".shape", out, false);
    if (!mapped) return mapped.error();
    if (!mapped.value()) return invalid(path + ".shape", "neither a sphere nor a capsule");

    const std::string ext_path = path + ".extensions.VRMC_springBone_extended_collider.shape";
    const auto exts = collider.find("extensions");
    if (exts != collider.end() && exts->is_object() && exts->contains("VRMC_springBone_extended_collider")) {
        const json& ext = (*exts)["VRMC_springBone_extended_collider"];
        if (ext.is_object() && ext.contains("shape") && ext["shape"].is_object()) {
            VrmCollider extended = out;
            auto ok = shape(ext["shape"], ext_path, extended, true);
            if (!ok) return ok.error();
            if (ok.value()) {
                out = extended;  // the extension's shape replaces the base one, its fallback
            } else {
                warn(ext_path, "unknown shape: the base shape is used");
            }
        }
    }
    out_.colliders.push_back(out);
    return {};
}

}  // namespace kodawari::gltf::vrm_detail
