// Points as a glTF (kodawari/export/export.hpp's write_points_glb): the one output that fits any
// domain whose instances are points moving frame by frame (a test domain's particles, a
// new domain before it has a glTF of its own). One node per point with a shared box mesh
// and a LINEAR translation channel (glTF 2.0 §3.11); the first frame is the rest pose.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "export/gltf_common.hpp"
#include "kodawari/export/export.hpp"
#include "kodawari/core/version.hpp"

namespace kodawari {

Result<void> write_points_glb(const std::string& path, const std::string& name, float fps, std::uint32_t frames,
                              std::span<const glm::vec3> positions, float size) {
    using namespace gltf;
    if (frames == 0) return make_error(Error::Kind::InvalidInput, path + ": cannot write an animation of 0 frames");
    if (!(fps > 0.0f) || !std::isfinite(fps)) {
        return make_error(Error::Kind::InvalidInput, path + ": fps: expected a finite number > 0, got " + std::to_string(fps));
    }
    if (!(size > 0.0f) || !std::isfinite(size)) {
        return make_error(Error::Kind::InvalidInput, path + ": size: expected a finite number > 0, got " + std::to_string(size));
    }
    if (positions.size() % frames != 0) {
        return make_error(Error::Kind::InvalidInput, path + ": expected frames x points positions (" + std::to_string(frames) +
                                                         " frames), got " + std::to_string(positions.size()));
    }
    const std::size_t count = positions.size() / frames;
    for (std::size_t i = 0; i < positions.size(); ++i) {
        const glm::vec3& p = positions[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
            return make_error(Error::Kind::InvalidInput, path + ": point " + std::to_string(i % count) + " at frame " +
                                                             std::to_string(i / count) + " is not finite");
        }
    }
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "kodawari " + std::string(version());
    model.buffers.emplace_back();
    BufferWriter writer(model.buffers[0].data);
    tinygltf::Material material;
    material.name = "point";
    material.pbrMetallicRoughness.baseColorFactor = {0.2, 0.55, 0.85, 1.0};
    material.pbrMetallicRoughness.metallicFactor = 0.0;
    model.materials.push_back(material);
    const float h = size / 2.0f;
    const int mesh = add_mesh(model, writer, box({-h, -h, -h}, {h, h, h}), 0, "point");

    // Key times, then each point's translations over every frame (item-major, as a
    // channel wants them).
    std::vector<float> times(frames);
    for (std::uint32_t f = 0; f < frames; ++f) times[f] = static_cast<float>(f) / fps;
    const std::size_t time_offset = writer.append(times.data(), times.size() * sizeof(float));
    const int time_view = add_buffer_view(model, time_offset, times.size() * sizeof(float), 0);
    const int time_accessor = add_accessor(model, time_view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_SCALAR);
    model.accessors[static_cast<std::size_t>(time_accessor)].minValues = {0.0};
    model.accessors[static_cast<std::size_t>(time_accessor)].maxValues = {static_cast<double>(times.back())};

    tinygltf::Node root;
    root.name = name;
    tinygltf::Animation animation;
    animation.name = "simulation";
    std::vector<Vec3> keys(frames);
    for (std::size_t i = 0; i < count; ++i) {
        for (std::uint32_t f = 0; f < frames; ++f) {
            const glm::vec3& p = positions[std::size_t{f} * count + i];
            keys[f] = {p.x, p.y, p.z};
        }
        const std::size_t offset = writer.append(keys.data(), keys.size() * sizeof(Vec3));
        const int view = add_buffer_view(model, offset, keys.size() * sizeof(Vec3), 0);
        const int accessor = add_accessor(model, view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_VEC3);
        tinygltf::Node node;
        node.name = name + "." + std::to_string(i);
        node.mesh = mesh;
        node.translation = {keys[0][0], keys[0][1], keys[0][2]};
        const int index = static_cast<int>(model.nodes.size()) + 1;  // the root goes first
        root.children.push_back(index);
        add_linear_channel(animation, time_accessor, accessor, index, "translation");
        model.nodes.push_back(std::move(node));
    }
    model.nodes.insert(model.nodes.begin(), std::move(root));
    if (!animation.channels.empty()) model.animations.push_back(std::move(animation));
    tinygltf::Scene scene;
    scene.name = name;
    scene.nodes.push_back(0);
    model.scenes.push_back(std::move(scene));
    model.defaultScene = 0;
    return write_file_atomically(path, [&](AtomicFile& file) { return write_glb(file, model); });
}

}  // namespace kodawari
