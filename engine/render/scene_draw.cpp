#include "kodawari/render/scene_draw.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>


namespace kodawari::render {

CameraView scene_camera(const Scene& scene, std::uint32_t frame) {
    const float fps = scene.fps > 0.0f ? scene.fps : 60.0f;
    const rods::CameraPose pose = rods::camera_pose(scene.camera.motion, static_cast<float>(frame) / fps);
    CameraView view;
    view.position = pose.position;
    // The pose's forward is what the view weights use; the target may coincide with the
    // position, so look along forward.
    view.target = pose.position + pose.forward;
    view.fov_deg = scene.camera.fov_deg;
    const float distance = glm::length(pose.target - pose.position);
    view.near = std::clamp(0.01f * distance, 0.01f, 1.0f);
    view.far = 1000.0f * view.near;
    // Orthographic: as tall as the perspective frustum at the target (rods::ImageCamera's
    // convention, which `kodawari sketch` uses too), 1 m where the target is the eye.
    view.orthographic = pose.projection == rods::Camera::Projection::Orthographic;
    view.ortho_height = distance > 1e-6f ? 2.0f * distance * std::tan(0.5f * glm::radians(view.fov_deg)) : 1.0f;
    if (view.orthographic) {
        // Depth is linear: a deep range costs no precision near the eye.
        view.near = 0.01f;
        view.far = 1e4f;
    }
    return view;
}

void add_ground_grid(DrawList& list, std::span<const glm::vec3> points) {
    glm::vec2 lo{0.0f}, hi{0.0f};
    for (const glm::vec3& p : points) {
        if (!std::isfinite(p.x) || !std::isfinite(p.z)) continue;
        lo = glm::min(lo, glm::vec2(p.x, p.z));
        hi = glm::max(hi, glm::vec2(p.x, p.z));
    }
    const glm::vec2 center = 0.5f * (lo + hi);
    const float half = std::max(3.0f, 0.5f * std::max(hi.x - lo.x, hi.y - lo.y) * 1.3f + 2.0f);
    // A round spacing giving 10 to 25 lines each way.
    const float rough = 2.0f * half / 10.0f;
    const float decade = std::pow(10.0f, std::floor(std::log10(rough)));
    float spacing = decade;
    for (const float m : {1.0f, 2.0f, 5.0f, 10.0f}) {
        if (m * decade <= rough) spacing = m * decade;
    }
    const float x0 = std::floor((center.x - half) / spacing) * spacing, x1 = std::ceil((center.x + half) / spacing) * spacing;
    const float z0 = std::floor((center.y - half) / spacing) * spacing, z1 = std::ceil((center.y + half) / spacing) * spacing;
    const int nx = static_cast<int>(std::lround((x1 - x0) / spacing)), nz = static_cast<int>(std::lround((z1 - z0) / spacing));
    for (int i = 0; i <= nx; ++i) {
        const float x = x0 + spacing * static_cast<float>(i);
        list.add_line({x, 0.0f, z0}, {x, 0.0f, z1}, kGridColor);
    }
    for (int i = 0; i <= nz; ++i) {
        const float z = z0 + spacing * static_cast<float>(i);
        list.add_line({x0, 0.0f, z}, {x1, 0.0f, z}, kGridColor);
    }
}

namespace {

bool has_mesh(const gltf::Character& character) {
    return std::any_of(character.nodes.begin(), character.nodes.end(), [&](const gltf::Node& n) {
        return n.mesh >= 0 && !character.meshes[static_cast<std::size_t>(n.mesh)].triangles.empty();
    });
}

// A rigged instance's own meshes, skinned on the CPU (glTF §3.7.3: each vertex moved by
// the weighted joint matrices world(joint) x inverseBindMatrix), flat shaded. Returns
// false when the character has no mesh to show (then its bones are drawn).
bool add_skinned_meshes(DrawList& list, const RodScene& scene, std::uint32_t c, std::uint32_t frame,
                        const ChainSnapshot* snapshot, gltf::Pose& pose, std::vector<glm::mat4>& world) {
    const gltf::Character& ch = *scene.characters[scene.instances[c].character].rig;
    if (!has_mesh(ch) || snapshot == nullptr || snapshot->positions.size() < scene.world.joint_count) return false;
    scene.rigged_world(c, frame, snapshot->positions, snapshot->orientations, pose, world);
    std::vector<glm::mat4> joint_matrices;
    std::vector<glm::vec3> skinned;
    for (std::size_t n = 0; n < ch.nodes.size(); ++n) {
        const gltf::Node& node = ch.nodes[n];
        if (node.mesh < 0) continue;
        const gltf::Skin* skin = node.skin >= 0 ? &ch.skins[static_cast<std::size_t>(node.skin)] : nullptr;
        joint_matrices.clear();
        if (skin != nullptr) {
            for (std::size_t j = 0; j < skin->joints.size(); ++j) {
                joint_matrices.push_back(world[static_cast<std::size_t>(skin->joints[j])] * skin->inverse_bind_matrices[j]);
            }
        }
        for (const gltf::Mesh::Triangles& t : ch.meshes[static_cast<std::size_t>(node.mesh)].triangles) {
            skinned.resize(t.positions.size());
            for (std::size_t v = 0; v < t.positions.size(); ++v) {
                const glm::vec4 p(t.positions[v], 1.0f);
                if (skin == nullptr || t.joints.empty()) {
                    skinned[v] = glm::vec3(world[n] * p);
                    continue;
                }
                glm::vec3 sum(0.0f);
                float total = 0.0f;
                for (int k = 0; k < 4; ++k) {
                    const float w = t.weights[v][k];
                    const std::uint32_t j = t.joints[v][k];
                    if (w <= 0.0f || j >= joint_matrices.size()) continue;
                    sum += w * glm::vec3(joint_matrices[j] * p);
                    total += w;
                }
                skinned[v] = total > 0.0f ? sum / total : glm::vec3(world[n] * p);
            }
            const glm::vec3 color(t.color);
            for (std::size_t i = 0; i + 2 < t.indices.size(); i += 3) {
                const glm::vec3& a = skinned[t.indices[i]];
                const glm::vec3& b = skinned[t.indices[i + 1]];
                const glm::vec3& d = skinned[t.indices[i + 2]];
                list.add_lit_triangle(a, b, d, glm::cross(b - a, d - a), color);
            }
        }
    }
    return true;
}

}  // namespace

void add_characters(DrawList& list, const RodScene& scene, std::uint32_t frame, const ChainSnapshot* snapshot,
                    const rods::RodFrame* kinematic) {
    std::vector<rods::Transform> joints;
    gltf::Pose pose;
    std::vector<glm::mat4> world_matrices;
    for (std::uint32_t c = 0; c < scene.instances.size(); ++c) {
        // Skinned meshes where the character has them, otherwise bones.
        if (scene.characters[scene.instances[c].character].rig &&
            add_skinned_meshes(list, scene, c, frame, snapshot, pose, world_matrices)) {
            continue;
        }
        scene.joint_poses(c, frame, joints);
        const auto& parents = scene.joint_parents(c);
        for (std::size_t j = 0; j < joints.size() && j < parents.size(); ++j) {
            if (parents[j] < 0) continue;
            list.add_segment(joints[static_cast<std::size_t>(parents[j])].position, joints[j].position, 0.012f, 2.0f, kBoneColor);
        }
    }
    if (kinematic != nullptr) {
        for (const rods::Capsule& capsule : kinematic->colliders) {
            list.add_circle(capsule.a, capsule.radius, kColliderColor);
            if (glm::length(capsule.b - capsule.a) > 1e-6f) {
                list.add_circle(capsule.b, capsule.radius, kColliderColor);
                list.add_line(capsule.a, capsule.b, kColliderColor);
            }
        }
    }
}

bool needs_snapshot(const RodScene& scene) {
    for (const CharacterInstance& instance : scene.instances) {
        const auto& rig = scene.characters[instance.character].rig;
        if (rig && has_mesh(*rig)) return true;
    }
    return false;
}

std::vector<glm::vec3> content_points(const RodScene* scene, const rods::RodFrame* frame, const birds::BirdWorld* birds) {
    std::vector<glm::vec3> points;
    if (scene != nullptr) {
        for (const CharacterInstance& instance : scene->instances) points.push_back(instance.placement.position);
    }
    if (frame != nullptr) {
        for (const rods::Transform& root : frame->roots) points.push_back(root.position);
    }
    if (birds != nullptr) {
        for (const gpu::vec4& p : birds->control_points) points.emplace_back(p.x, p.y, p.z);
    }
    return points;
}

}  // namespace kodawari::render
