// Sketching a chain's shape from a view (SPEC A.6). Computed in double: the joints are
// found in world space (metres, far from the origin) and then expressed in the chain
// root's frame, where a segment is millimetres long; float would cost the segment lengths
// their 1e-5 relative accuracy.

#include "kodawari/rods/sketch.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <string>

namespace kodawari::rods {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The camera's orthonormal basis: right, up (of the picture), forward.
struct Basis {
    glm::dvec3 right, up, forward;
};

Basis camera_basis(const ImageCamera& c) {
    const glm::dvec3 forward = glm::normalize(glm::dvec3(c.target) - glm::dvec3(c.position));
    glm::dvec3 world_up(0.0, 1.0, 0.0);
    // Looking straight up or down, +Y gives no right vector.
    if (glm::length(glm::cross(forward, world_up)) < 1e-6) world_up = glm::dvec3(0.0, 0.0, -1.0);
    const glm::dvec3 right = glm::normalize(glm::cross(forward, world_up));
    return Basis{right, glm::cross(right, forward), forward};
}

// Pixels per metre on the image plane at depth 1 (perspective) or everywhere (orthographic).
double pixel_scale(const ImageCamera& c) {
    const double half_fov = static_cast<double>(c.fov_deg) * kPi / 360.0;
    if (c.projection == Camera::Projection::Perspective) return (static_cast<double>(c.height) / 2.0) / std::tan(half_fov);
    double h = static_cast<double>(c.ortho_height);
    if (h <= 0.0) h = 2.0 * glm::length(glm::dvec3(c.target) - glm::dvec3(c.position)) * std::tan(half_fov);
    return static_cast<double>(c.height) / h;
}

bool valid_camera(const ImageCamera& c) {
    const auto finite3 = [](glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    return c.width > 0 && c.height > 0 && c.fov_deg > 0.0f && c.fov_deg < 180.0f && finite3(c.position) &&
           finite3(c.target) && glm::length(glm::dvec3(c.target) - glm::dvec3(c.position)) > 1e-9 &&
           std::isfinite(c.ortho_height) && c.ortho_height >= 0.0f;
}

// The point of the plane at `depth` (along forward) that projects to `pixel`.
glm::dvec3 unproject(const ImageCamera& c, const Basis& b, double scale, glm::dvec2 pixel, double depth) {
    const double x = pixel.x - static_cast<double>(c.width) / 2.0;
    const double y = static_cast<double>(c.height) / 2.0 - pixel.y;
    const double per_pixel = c.projection == Camera::Projection::Perspective ? depth / scale : 1.0 / scale;
    return glm::dvec3(c.position) + b.right * (x * per_pixel) + b.up * (y * per_pixel) + b.forward * depth;
}

Error invalid(const std::string& message) { return make_error(Error::Kind::InvalidInput, "sketch: " + message); }

}  // namespace

ImageCamera ImageCamera::from_pose(const CameraPose& pose, float fov_deg, std::uint32_t width, std::uint32_t height) {
    ImageCamera c;
    c.projection = pose.projection;
    c.position = pose.position;
    // A pose whose target meets its position keeps its forward (kinematics.hpp).
    c.target = glm::length(pose.target - pose.position) > 1e-6f ? pose.target : pose.position + pose.forward;
    c.fov_deg = fov_deg;
    c.width = width;
    c.height = height;
    return c;
}

Camera ImageCamera::view_camera() const {
    return Camera{projection, position, glm::vec3(glm::normalize(glm::dvec3(target) - glm::dvec3(position)))};
}

glm::dvec3 project_to_pixels(const ImageCamera& camera, glm::dvec3 world) {
    assert(valid_camera(camera));
    const Basis b = camera_basis(camera);
    const double scale = pixel_scale(camera);
    const glm::dvec3 v = world - glm::dvec3(camera.position);
    const double depth = glm::dot(v, b.forward);
    const double per_metre = camera.projection == Camera::Projection::Perspective ? scale / depth : scale;
    return {static_cast<double>(camera.width) / 2.0 + glm::dot(v, b.right) * per_metre,
            static_cast<double>(camera.height) / 2.0 - glm::dot(v, b.up) * per_metre, depth};
}

double distance_to_polyline(glm::dvec2 point, std::span<const glm::dvec2> stroke) {
    assert(!stroke.empty());
    double best = glm::length(point - stroke[0]);
    for (std::size_t i = 1; i < stroke.size(); ++i) {
        const glm::dvec2 a = stroke[i - 1];
        const glm::dvec2 d = stroke[i] - a;
        const double dd = glm::dot(d, d);
        const double t = dd > 0.0 ? std::clamp(glm::dot(point - a, d) / dd, 0.0, 1.0) : 0.0;
        best = std::min(best, glm::length(point - (a + t * d)));
    }
    return best;
}

Result<SketchResult> sketch_view_example(const SketchInput& input) {
    // --- checks: everything here may come from a file or a user's stroke
    if (!valid_camera(input.camera)) {
        return invalid("the camera needs a size above 0, a field of view in (0, 180) degrees, finite values and a "
                       "target away from its position");
    }
    if (input.lengths.empty() || input.lengths.size() + 1 > kMaxChainJoints) {
        return invalid("a chain has 2 to " + std::to_string(kMaxChainJoints) + " joints, got " +
                       std::to_string(input.lengths.size() + 1));
    }
    for (float l : input.lengths) {
        if (!(std::isfinite(l) && l > 0.0f)) return invalid("segment lengths must be finite and > 0");
    }
    if (!(input.influence > 0.0f && input.influence <= kMaxInfluence)) {
        return invalid("the influence must be in (0, " + std::to_string(static_cast<int>(kMaxInfluence)) + "]");
    }
    if (input.stroke.size() < 2) {
        return invalid("the stroke needs at least 2 points, got " + std::to_string(input.stroke.size()));
    }
    for (std::size_t i = 0; i < input.stroke.size(); ++i) {
        if (!std::isfinite(input.stroke[i].x) || !std::isfinite(input.stroke[i].y)) {
            return invalid("stroke point " + std::to_string(i) + " is not finite");
        }
        if (std::abs(input.stroke[i].x) > kMaxStrokePixels || std::abs(input.stroke[i].y) > kMaxStrokePixels) {
            return invalid("stroke point " + std::to_string(i) + " lies more than 1e6 px from the image");
        }
    }

    const ImageCamera& cam = input.camera;
    const Basis basis = camera_basis(cam);
    const double scale = pixel_scale(cam);
    const glm::dvec3 root(input.root.position);
    const glm::dvec3 root_px = project_to_pixels(cam, root);
    const double depth = root_px.z;
    if (cam.projection == Camera::Projection::Perspective && !(depth > 1e-6)) {
        return invalid("the chain root is behind the camera (depth " + std::to_string(depth) +
                       " m); it has no place in the picture");
    }

    SketchResult out;
    // The stroke starts at the root's projection: translated, so the drawn shape is kept.
    out.stroke_offset = glm::dvec2(root_px) - input.stroke.front();
    for (glm::dvec2 p : input.stroke) {
        p += out.stroke_offset;
        // Repeated points (a pen that rests) make pieces with no direction; closer than a
        // thousandth of a pixel counts as repeated.
        if (out.stroke.empty() || glm::length(p - out.stroke.back()) > 1e-3) out.stroke.push_back(p);
    }
    if (out.stroke.size() < 2) return invalid("the stroke has no length (all its points are the same)");

    // The stroke on the plane through j_0 parallel to the image (SPEC A.6), in metres.
    std::vector<glm::dvec3> path;
    path.reserve(out.stroke.size());
    path.push_back(root);
    for (std::size_t i = 1; i < out.stroke.size(); ++i) path.push_back(unproject(cam, basis, scale, out.stroke[i], depth));

    // Walk along the stroke: each joint is the first point after the previous one at
    // distance l_i from it. The distance to the previous joint starts below l_i (at 0)
    // on its own piece, so on each piece the first crossing is the larger root of
    // |a + u d - prev|^2 = l^2; the last piece extends without end (past the stroke's
    // end, continue along its last direction), where the root always exists.
    const std::size_t n = input.lengths.size() + 1;
    out.world_positions.assign(1, root);
    std::size_t piece = 0;  // the stroke piece path[piece] -> path[piece + 1]
    double u_from = 0.0;    // where on it the previous joint lies
    std::uint32_t on_stroke = 1;
    double used_px = 0.0;   // stroke length up to the last joint on it
    for (std::size_t i = 1; i < n; ++i) {
        const glm::dvec3 prev = out.world_positions.back();
        const double l = static_cast<double>(input.lengths[i - 1]);
        for (;;) {
            const bool last = piece + 2 == path.size();
            const glm::dvec3 a = path[piece];
            const glm::dvec3 d = path[piece + 1] - a;
            const double qa = glm::dot(d, d);
            const double qb = 2.0 * glm::dot(d, a - prev);
            const double qc = glm::dot(a - prev, a - prev) - l * l;
            const double disc = std::max(0.0, qb * qb - 4.0 * qa * qc);
            const double u = (-qb + std::sqrt(disc)) / (2.0 * qa);
            if (u <= 1.0 || last) {
                // Numerically u could dip below u_from only if the distance had already
                // reached l there, which the previous step rules out; clamp for safety.
                const double uu = std::max(u, u_from);
                out.world_positions.push_back(a + uu * d);
                u_from = uu;
                if (uu <= 1.0) {
                    ++on_stroke;
                    used_px = 0.0;
                    for (std::size_t k = 0; k < piece; ++k) used_px += glm::length(out.stroke[k + 1] - out.stroke[k]);
                    used_px += uu * glm::length(out.stroke[piece + 1] - out.stroke[piece]);
                }
                break;
            }
            ++piece;
            u_from = 0.0;
        }
    }
    double stroke_px = 0.0;
    for (std::size_t k = 1; k < out.stroke.size(); ++k) stroke_px += glm::length(out.stroke[k] - out.stroke[k - 1]);
    out.joints_on_stroke = on_stroke;
    out.stroke_used = on_stroke < n ? 1.0 : std::clamp(used_px / stroke_px, 0.0, 1.0);

    // Diagnostics: reprojection against the stroke as used.
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec2 px(project_to_pixels(cam, out.world_positions[i]));
        out.pixels.push_back(px);
        const double e = distance_to_polyline(px, out.stroke);
        if (i < on_stroke) {
            out.max_error_px = std::max(out.max_error_px, e);
        } else {
            out.max_overrun_px = std::max(out.max_overrun_px, e);
        }
    }

    // Into the chain root's frame; joint 0 exactly at its origin (the scene format's rule).
    const glm::dquat to_root = glm::conjugate(glm::dquat(input.root.rotation));
    out.shape.positions.resize(n);
    out.shape.positions[0] = glm::vec3(0.0f);
    for (std::size_t i = 1; i < n; ++i) out.shape.positions[i] = glm::vec3(to_root * (out.world_positions[i] - root));
    // The scene format's default orientations: +Y along the joint's segment (the last
    // joint along the last one), by the shortest arc.
    out.shape.orientations.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t seg = std::min(i, n - 2);
        const glm::vec3 dir = glm::vec3(glm::normalize(to_root * (out.world_positions[seg + 1] - out.world_positions[seg])));
        out.shape.orientations[i] = shortest_arc(glm::vec3(0.0f, 1.0f, 0.0f), dir);
    }

    // The view direction d of SPEC A.3, as the blend will measure it.
    out.view.direction = view_direction(cam.view_camera(), input.reference.position, input.reference.rotation);
    out.view.influence = input.influence;
    return out;
}

}  // namespace kodawari::rods
