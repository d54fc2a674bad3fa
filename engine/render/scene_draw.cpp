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

bool draws_skinned(const gltf::Character& character) {
    return std::any_of(character.nodes.begin(), character.nodes.end(), [&](const gltf::Node& n) {
        return n.mesh >= 0 && !character.meshes[static_cast<std::size_t>(n.mesh)].triangles.empty();
    });
}

void add_contact_shadow(DrawList& list, std::span<const rods::Transform> joints) {
    if (joints.empty()) return;
    float low = joints[0].position.y, high = low;
    for (const rods::Transform& j : joints) {
        low = std::min(low, j.position.y);
        high = std::max(high, j.position.y);
    }
    // As wide as a body of the skeleton's height is, fading out as the lowest joint
    // rises off the ground by that height (the skeleton's joints, not its surface: the
    // feet or hips are a few centimetres to a few decimetres up).
    const float height = std::max(high - std::max(low, 0.0f), 0.1f);
    const float lift = std::max(low, 0.0f);
    const float opacity = kShadowOpacity * std::clamp(1.0f - lift / height, 0.0f, 1.0f);
    // Under the joints' centroid, not the root joint: a rigged character's root node
    // stays where it was placed while a clip with root motion (a walk round a circle)
    // carries the hips and everything else away from it.
    glm::vec3 centre(0.0f);
    for (const rods::Transform& j : joints) centre += j.position / static_cast<float>(joints.size());
    if (!(opacity > 0.0f) || !std::isfinite(centre.x) || !std::isfinite(centre.z)) return;
    list.add_ground_shadow(centre, std::clamp(0.3f * height, 0.1f, 1.5f), opacity);
}

void add_characters(DrawList& list, const RodScene& scene, std::uint32_t frame) {
    std::vector<rods::Transform> joints;
    for (std::uint32_t c = 0; c < scene.instances.size(); ++c) {
        scene.joint_poses(c, frame, joints);
        add_contact_shadow(list, joints);
        // Rigged characters with meshes are the renderer's skinned-mesh layer.
        const auto& rig = scene.characters[scene.instances[c].character].rig;
        if (rig && draws_skinned(*rig)) continue;
        const auto& parents = scene.joint_parents(c);
        for (std::size_t j = 0; j < joints.size() && j < parents.size(); ++j) {
            if (parents[j] < 0) continue;
            list.add_segment(joints[static_cast<std::size_t>(parents[j])].position, joints[j].position, 0.012f, 2.0f, kBoneColor);
        }
    }
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
