#pragma once
// What the files of the VRM spring-bone reader share (not public): the reader of
// kodawari/gltf/vrm.hpp read_vrm_springs(), whose members are defined by job in vrm.cpp
// (the springs of VRMC_springBone 1.0 and VRM 0.x as chains), vrm_colliders.cpp (the
// colliders) and vrm_fields.cpp (every checked JSON field, the joints' settings and limits).

#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "kodawari/gltf/vrm.hpp"

namespace kodawari::gltf::vrm_detail {

using nlohmann::json;

inline std::string at(const std::string& path, std::size_t index) { return path + "[" + std::to_string(index) + "]"; }

// Per-joint VRM parameters (VRM 1.0 joint, or a VRM 0.x bone group).
struct Settings {
    float hit_radius = 0.0f;
    float stiffness = 1.0f;
    float gravity_power = 0.0f;
    glm::vec3 gravity_dir{0.0f, -1.0f, 0.0f};
    float drag = 0.5f;
    rods::AngleLimit limit;  // VRMC_springBone_limit on the joint (VRM 1.0 only)
};

class Reader {
public:
    explicit Reader(const animation::Character& character) : c_(character), rest_(animation::rest_pose(character)) {}

    // vrm.cpp
    Result<VrmSprings> read();

private:
    const animation::Character& c_;
    animation::Pose rest_;
    VrmSprings out_;

    [[nodiscard]] Error invalid(const std::string& path, const std::string& what) const {
        return make_error(Error::Kind::InvalidInput, c_.source + ": " + path + ": " + what);
    }
    void warn(const std::string& path, const std::string& what) { out_.warnings.push_back(c_.source + ": " + path + ": " + what); }

    // vrm_fields.cpp: fields of JSON types, checked, and the joints' settings and limits.
    Result<const json*> member(const json& parent, const std::string& key, const std::string& path, bool required,
                               bool (json::*is)() const noexcept, const char* what);
    Result<const json*> object(const json& parent, const std::string& key, const std::string& path, bool required);
    Result<const json*> array(const json& parent, const std::string& key, const std::string& path, bool required);
    Result<float> number(const json& parent, const std::string& key, const std::string& path, float fallback);
    Result<rods::AngleLimit> limit(const json& joint, const std::string& path);
    Result<float> radius(const json& parent, const std::string& path, float fallback);
    Result<glm::vec3> vec3(const json& parent, const std::string& key, const std::string& path, glm::vec3 fallback);
    Result<glm::vec3> vec3_object(const json& parent, const std::string& key, const std::string& path, glm::vec3 fallback);
    Result<std::size_t> index(const json& parent, const std::string& key, const std::string& path, std::size_t count,
                              const std::string& what);
    Result<std::size_t> index_value(const json& value, const std::string& path, std::size_t count, const std::string& what);
    Result<Settings> settings(const json& obj, const std::string& path, const Settings& defaults, bool vrm0);

    // vrm_colliders.cpp: VRM 1.0 colliders and their shapes.
    Result<bool> shape(const json& shape_obj, const std::string& path, VrmCollider& out, bool extended);
    Result<bool> flag(const json& parent, const std::string& key, const std::string& path, bool read);
    Result<void> read_collider_1(const json& collider, const std::string& path);

    // vrm.cpp: the springs, VRMC_springBone 1.0 and VRM 0.x, as chains.
    Result<void> add_chain(std::vector<int> nodes, std::vector<Settings> bones, std::vector<std::size_t> colliders, int center,
                           const std::string& path);
    Result<void> read_1(const json& ext, const std::string& path);
    Result<void> read_0(const json& secondary, const std::string& path);
};

}  // namespace kodawari::gltf::vrm_detail
