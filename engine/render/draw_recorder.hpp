#pragma once
// What domains draw through render::Draw (kodawari/render/draw.hpp), kept until cleared
// and replayed into each frame's draw list, where the camera and image size are known
// (minimum sizes in pixels, camera-facing ribbons and discs).

#include <functional>
#include <span>
#include <vector>

#include "kodawari/render/renderer.hpp"

namespace kodawari::render {

class DrawRecorder {
public:
    void lines(std::span<const glm::vec3> pairs, Rgba8 color);
    void tubes(std::span<const glm::vec3> points, std::span<const Polyline> polylines, float min_px);
    void capsules(std::span<const Capsule> capsules, Rgba8 color);
    void discs(std::span<const glm::vec3> centers, float radius, Rgba8 color, float min_px);
    void meshes(const MeshView& mesh, std::span<const glm::mat4> transforms, Rgba8 color);

    void clear() { ops_.clear(); }
    [[nodiscard]] bool empty() const { return ops_.empty(); }
    /// Adds everything drawn to `list`; `rows_scale` scales the minimum pixel sizes (given
    /// at 720 rows).
    void replay(DrawList& list, float rows_scale) const;

private:
    std::vector<std::function<void(DrawList&, float)>> ops_;
};

}  // namespace kodawari::render
