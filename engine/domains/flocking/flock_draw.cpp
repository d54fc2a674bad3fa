// The obstacles of the flocking domain drawn as the objects they stand for (a balloon, a
// tower, a cable, a wall, a sea), so that a render or the viewer shows what the birds
// turn round rather than birds swerving about nothing.
#include "domains/flocking/flock_draw.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "kodawari/domains/flocking.hpp"
#include "render/grid_spacing.hpp"

namespace kodawari::flocking {

namespace {

glm::vec3 xyz(const gpu::vec4& v) { return {v.x, v.y, v.z}; }

// The plane through `point` with unit `normal` as a square grid of lines, centred where
// the middle of `extent` falls on it and somewhat wider than the extent (a plane has no
// edge; the flock meets the part of it near where it flies).
void add_plane(std::vector<glm::vec3>& pairs, const glm::vec3& point, const glm::vec3& normal, const DrawExtent& extent) {
    // The ground grid is drawn on the ground already (y = 0): the same lines twice would
    // fight in the depth test.
    if (std::abs(normal.y) > 0.999f && std::abs(point.y) < 1e-3f) return;
    const bool empty = extent.lo.x > extent.hi.x;
    const glm::vec3 middle = empty ? point : 0.5f * (extent.lo + extent.hi);
    const glm::vec3 centre = middle - glm::dot(middle - point, normal) * normal;
    const float half = std::max(10.0f, empty ? 0.0f : 0.75f * glm::length(extent.hi - extent.lo));
    const glm::vec3 helper = std::abs(normal.y) < 0.9f ? glm::vec3(0.0f, 1.0f, 0.0f) : glm::vec3(1.0f, 0.0f, 0.0f);
    const glm::vec3 u = glm::normalize(glm::cross(normal, helper)), v = glm::cross(normal, u);
    const float spacing = render::grid_spacing(2.0f * half);
    const int lines = static_cast<int>(std::ceil(half / spacing));
    const float reach = spacing * static_cast<float>(lines);
    for (int i = -lines; i <= lines; ++i) {
        const float at = spacing * static_cast<float>(i);
        pairs.insert(pairs.end(), {centre + at * u - reach * v, centre + at * u + reach * v});
        pairs.insert(pairs.end(), {centre + at * v - reach * u, centre + at * v + reach * u});
    }
}

}  // namespace

DrawExtent draw_extent(const FlockWorld& world) {
    constexpr float kInf = std::numeric_limits<float>::infinity();
    DrawExtent e{glm::vec3(kInf), glm::vec3(-kInf)};
    const auto add = [&](const glm::vec3& p) {
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return;
        e.lo = glm::min(e.lo, p);
        e.hi = glm::max(e.hi, p);
    };
    for (const gpu::FlockStateGpu& s : world.initial) add(xyz(s.position));
    for (const gpu::vec4& c : world.routes.control_points) add(xyz(c));
    return e;
}

void draw_obstacles(render::Draw& draw, std::span<const gpu::FlockAgentGpu> agents, const DrawExtent& extent) {
    std::vector<render::Capsule> solids;
    std::vector<glm::vec3> pairs;
    for (const gpu::FlockAgentGpu& a : agents) {
        const float kind = a.kind_weight.x;
        // FlockAgentGpu (kodawari/shared/flocking.h): a sphere's and a capsule's radius is
        // position.w; a capsule's other end and a plane's unit normal are velocity.xyz.
        if (kind == KW_FLOCK_AGENT_SPHERE) {
            solids.push_back({xyz(a.position), xyz(a.position), a.position.w});
        } else if (kind == KW_FLOCK_AGENT_CAPSULE) {
            solids.push_back({xyz(a.position), xyz(a.velocity), a.position.w});
        } else if (kind == KW_FLOCK_AGENT_PLANE) {
            add_plane(pairs, xyz(a.position), xyz(a.velocity), extent);
        }
    }
    if (!solids.empty()) draw.capsules(solids, kObstacleColor);
    if (!pairs.empty()) draw.lines(pairs, kObstaclePlaneColor);
}

}  // namespace kodawari::flocking
