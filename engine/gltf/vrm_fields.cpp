// The VRM spring-bone reader's fields (vrm_reader.hpp): every JSON field it reads,
// checked, with problems naming the file and the JSON path (vrm.cpp), and the joints'
// settings and angle limits built from them.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

#include "gltf/vrm_reader.hpp"

namespace kodawari::gltf::vrm_detail {

// Fields. Absent optional fields take `fallback`; present ones must have the type.
// A member of JSON type `is` (an object, an array); nullptr when absent and optional.
Result<const json*> Reader::member(const json& parent, const std::string& key, const std::string& path, bool required,
                                   bool (json::*is)() const noexcept, const char* what) {
    const auto it = parent.find(key);
    if (it == parent.end()) {
        if (required) return invalid(path, "missing \"" + key + "\"");
        return static_cast<const json*>(nullptr);
    }
    if (!((*it).*is)()) return invalid(path + "." + key, std::string("expected ") + what);
    return &*it;
}

Result<const json*> Reader::object(const json& parent, const std::string& key, const std::string& path, bool required) {
    return member(parent, key, path, required, &json::is_object, "an object");
}

Result<const json*> Reader::array(const json& parent, const std::string& key, const std::string& path, bool required) {
    return member(parent, key, path, required, &json::is_array, "an array");
}

Result<float> Reader::number(const json& parent, const std::string& key, const std::string& path, float fallback) {
    const auto it = parent.find(key);
    if (it == parent.end()) return fallback;
    if (!it->is_number()) return invalid(path + "." + key, "expected a number");
    const auto v = it->get<double>();
    if (!std::isfinite(v)) return invalid(path + "." + key, "not finite");
    return static_cast<float>(v);
}

// A joint's VRMC_springBone_limit (1.0-draft): exactly one of cone {angle, rotation},
// hinge {angle, rotation}, spherical {pitch, yaw, rotation}; angles in radians, >= 0,
// read as pi (pitch, angle) or pi/2 (yaw) above those, as the draft says an
// implementation MUST; rotation a unit quaternion (x, y, z, w), normalized as written.
Result<rods::AngleLimit> Reader::limit(const json& joint, const std::string& path) {
    rods::AngleLimit out;
    const auto exts = joint.find("extensions");
    if (exts == joint.end() || !exts->is_object()) return out;
    const auto ext = exts->find("VRMC_springBone_limit");
    if (ext == exts->end()) return out;
    const std::string p = path + ".extensions.VRMC_springBone_limit";
    if (!ext->is_object()) return invalid(p, "expected an object");
    const auto lim = ext->find("limit");
    const char* kinds[3] = {"cone", "hinge", "spherical"};
    if (lim == ext->end() || !lim->is_object()) return invalid(p + ".limit", "expected an object with one of cone, hinge, spherical");
    int found = -1;
    for (int k = 0; k < 3; ++k) {
        if (!lim->contains(kinds[k])) continue;
        if (found >= 0) return invalid(p + ".limit", "more than one of cone, hinge, spherical");
        found = k;
    }
    if (found < 0) return invalid(p + ".limit", "expected one of cone, hinge, spherical");
    const json& shape = (*lim)[kinds[found]];
    const std::string sp = p + ".limit." + kinds[found];
    if (!shape.is_object()) return invalid(sp, "expected an object");
    auto angle = [&](const char* key, float most) -> Result<float> {
        if (!shape.contains(key)) return invalid(sp, std::string("missing \"") + key + "\"");
        auto v = number(shape, key, sp, 0.0f);
        if (!v) return v.error();
        if (v.value() < 0.0f) return invalid(sp + "." + key, "negative (" + std::to_string(v.value()) + " rad); at least 0");
        return std::min(v.value(), most);
    };
    if (found == 2) {
        out.kind = rods::LimitKind::Spherical;
        auto pitch = angle("pitch", rods::kMaxLimitAngle);
        if (!pitch) return pitch.error();
        auto yaw = angle("yaw", rods::kMaxLimitYaw);
        if (!yaw) return yaw.error();
        out.angle = pitch.value();
        out.yaw = yaw.value();
    } else {
        out.kind = found == 0 ? rods::LimitKind::Cone : rods::LimitKind::Hinge;
        auto a = angle("angle", rods::kMaxLimitAngle);
        if (!a) return a.error();
        out.angle = a.value();
    }
    if (const auto r = shape.find("rotation"); r != shape.end()) {
        const std::string rp = sp + ".rotation";
        if (!r->is_array() || r->size() != 4) return invalid(rp, "expected 4 numbers [x, y, z, w]");
        float q[4] = {};
        for (std::size_t i = 0; i < 4; ++i) {
            if (!(*r)[i].is_number() || !std::isfinite((*r)[i].get<double>())) return invalid(rp, "expected 4 finite numbers");
            q[i] = (*r)[i].get<float>();
        }
        const glm::quat rotation(q[3], q[0], q[1], q[2]);
        const float len = glm::length(rotation);
        if (!(len > 1e-6f)) return invalid(rp, "a zero quaternion; expected a unit one");
        out.rotation = rotation / len;
    }
    return out;
}

Result<float> Reader::radius(const json& parent, const std::string& path, float fallback) {
    auto r = number(parent, "radius", path, fallback);
    if (r && r.value() < 0.0f) return invalid(path + ".radius", "negative (" + std::to_string(r.value()) + ")");
    return r;
}

// A VRM 1.0 vec3: [x, y, z].
Result<glm::vec3> Reader::vec3(const json& parent, const std::string& key, const std::string& path, glm::vec3 fallback) {
    const auto it = parent.find(key);
    if (it == parent.end()) return fallback;
    const std::string p = path + "." + key;
    if (!it->is_array() || it->size() != 3) return invalid(p, "expected an array of 3 numbers");
    glm::vec3 v;
    for (std::size_t i = 0; i < 3; ++i) {
        if (!(*it)[i].is_number() || !std::isfinite((*it)[i].get<double>())) return invalid(at(p, i), "expected a finite number");
        v[static_cast<glm::length_t>(i)] = (*it)[i].get<float>();
    }
    return v;
}

// A VRM 0.x vec3: {"x": .., "y": .., "z": ..}, absent components 0.
Result<glm::vec3> Reader::vec3_object(const json& parent, const std::string& key, const std::string& path, glm::vec3 fallback) {
    const auto it = parent.find(key);
    if (it == parent.end()) return fallback;
    const std::string p = path + "." + key;
    if (!it->is_object()) return invalid(p, "expected an object {x, y, z}");
    glm::vec3 v(0.0f);
    for (glm::length_t i = 0; i < 3; ++i) {
        auto component = number(*it, std::string(1, "xyz"[i]), p, 0.0f);
        if (!component) return component.error();
        v[i] = component.value();
    }
    return v;
}

Result<std::size_t> Reader::index(const json& parent, const std::string& key, const std::string& path, std::size_t count,
                                  const std::string& what) {
    const auto it = parent.find(key);
    if (it == parent.end()) return invalid(path, "missing \"" + key + "\"");
    return index_value(*it, path + "." + key, count, what);
}

Result<std::size_t> Reader::index_value(const json& value, const std::string& path, std::size_t count, const std::string& what) {
    if (!value.is_number_integer()) return invalid(path, "expected an integer");
    const auto i = value.get<long long>();
    if (i < 0 || static_cast<unsigned long long>(i) >= count) {
        return invalid(path, what + " " + std::to_string(i) + " does not exist (" + std::to_string(count) + " of them)");
    }
    return static_cast<std::size_t>(i);
}

Result<Settings> Reader::settings(const json& obj, const std::string& path, const Settings& defaults, bool vrm0) {
    Settings s;
    auto hit = number(obj, "hitRadius", path, defaults.hit_radius);
    auto stiffness = number(obj, vrm0 ? "stiffiness" : "stiffness", path, defaults.stiffness);  // sic, VRM 0.x
    auto power = number(obj, "gravityPower", path, defaults.gravity_power);
    auto dir = vrm0 ? vec3_object(obj, "gravityDir", path, defaults.gravity_dir) : vec3(obj, "gravityDir", path, defaults.gravity_dir);
    auto drag = number(obj, "dragForce", path, defaults.drag);
    for (const Result<float>* r : {&hit, &stiffness, &power, &drag}) {
        if (!*r) return r->error();
    }
    if (!dir) return dir.error();
    s.hit_radius = std::max(hit.value(), 0.0f);
    s.stiffness = std::max(stiffness.value(), 0.0f);
    s.gravity_power = std::max(power.value(), 0.0f);
    // gravityDir is a unit vector by the spec; normalize what authors wrote.
    const float len = glm::length(dir.value());
    s.gravity_dir = len > 0.0f ? dir.value() / len : glm::vec3(0.0f);
    s.drag = drag.value();
    return s;
}

}  // namespace kodawari::gltf::vrm_detail
