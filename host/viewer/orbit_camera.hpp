#pragma once
// The viewer's camera: an orbit around a target, started from the scene's camera, giving
// the renderer's view and the rods' image camera (sketching, view-dependent shapes).
#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

#include "kodawari/render/renderer.hpp"
#include "kodawari/rods/kinematics.hpp"
#include "kodawari/rods/sketch.hpp"
#include "kodawari/scene/scene.hpp"

namespace kodawari::cli {

// An orbit camera around a target: yaw about +Y, pitch above the horizon, distance.
struct OrbitCamera {
    glm::vec3 target{0.0f};
    float yaw = 0.0f, pitch = 0.0f, distance = 3.0f, fov_deg = 50.0f;
    bool orthographic = false;  // as tall as the perspective frustum at the target (rods::ImageCamera)

    // The scene camera at `time` (s), orbiting its target (scene_camera() looks 1 m along
    // forward instead, which would make a tiny orbit), with its projection; a camera whose
    // target is its position orbits a point 10 m ahead.
    static OrbitCamera from(const Scene& scene, float time = 0.0f) {
        const rods::CameraPose pose = rods::camera_pose(scene.camera.motion, time);
        OrbitCamera c;
        c.orthographic = pose.projection == rods::Camera::Projection::Orthographic;
        c.fov_deg = scene.camera.fov_deg;
        c.target = glm::length(pose.target - pose.position) > 1e-3f ? pose.target : pose.position + 10.0f * pose.forward;
        const glm::vec3 offset = pose.position - c.target;
        c.distance = std::max(glm::length(offset), 1e-3f);
        c.pitch = std::asin(std::clamp(offset.y / c.distance, -1.0f, 1.0f));
        c.yaw = std::atan2(offset.x, offset.z);
        return c;
    }
    [[nodiscard]] glm::vec3 position() const {
        return target + distance * glm::vec3(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
    }
    [[nodiscard]] render::CameraView view() const {
        render::CameraView v;
        v.position = position();
        v.target = target;
        v.fov_deg = fov_deg;
        // Near 1% of the distance within [0.01, 1] m, as scene_camera; far at least 1 km, so
        // that zooming in on one character keeps the rest of a crowd in view.
        v.near = std::clamp(0.01f * distance, 0.01f, 1.0f);
        v.far = std::max(1000.0f * v.near, 1000.0f);
        v.orthographic = orthographic;
        v.ortho_height = 2.0f * distance * std::tan(0.5f * glm::radians(fov_deg));
        return v;
    }
    [[nodiscard]] rods::ImageCamera image(std::uint32_t w, std::uint32_t h) const {
        rods::ImageCamera c;
        c.projection = orthographic ? rods::Camera::Projection::Orthographic : rods::Camera::Projection::Perspective;
        c.position = position();
        c.target = target;
        c.fov_deg = fov_deg;
        c.width = w;
        c.height = h;
        return c;
    }
};

}  // namespace kodawari::cli
