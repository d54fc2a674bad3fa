#include "kodawari/domains/scene_draw.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>


namespace kodawari {

using render::CameraView;
using render::DrawList;
using render::Rgba8;


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

bool draws_skinned(const animation::Character& character) {
    return std::any_of(character.nodes.begin(), character.nodes.end(), [&](const animation::Node& n) {
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

namespace {

glm::vec3 lit(Rgba8 c) { return glm::vec3(c.r, c.g, c.b) / 255.0f; }

// A tube of `sides` flat-shaded lit faces from a to b, closed at both ends.
void add_tube(DrawList& list, const glm::vec3& a, const glm::vec3& b, float radius, Rgba8 color, int sides = 10) {
    const glm::vec3 axis = b - a;
    const float length = glm::length(axis);
    if (!(length > 0.0f)) return;
    const glm::vec3 t = axis / length;
    const glm::vec3 helper = std::abs(t.y) < 0.9f ? glm::vec3(0.0f, 1.0f, 0.0f) : glm::vec3(1.0f, 0.0f, 0.0f);
    const glm::vec3 e1 = glm::normalize(glm::cross(t, helper)), e2 = glm::cross(t, e1);
    const glm::vec3 c = lit(color);
    const auto around = [&](int i) {
        const float angle = 6.28318530718f * static_cast<float>(i) / static_cast<float>(sides);
        return std::cos(angle) * e1 + std::sin(angle) * e2;
    };
    for (int i = 0; i < sides; ++i) {
        const glm::vec3 u0 = around(i), u1 = around(i + 1), n = glm::normalize(u0 + u1);
        list.add_lit_triangle(a + radius * u0, a + radius * u1, b + radius * u1, n, c);
        list.add_lit_triangle(a + radius * u0, b + radius * u1, b + radius * u0, n, c);
        list.add_lit_triangle(a, a + radius * u1, a + radius * u0, -t, c);
        list.add_lit_triangle(b, b + radius * u0, b + radius * u1, t, c);
    }
}

void add_quad(DrawList& list, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const glm::vec3& d, Rgba8 color) {
    const glm::vec3 n = glm::cross(b - a, d - a);
    list.add_lit_triangle(a, b, c, n, lit(color));
    list.add_lit_triangle(a, c, d, n, lit(color));
}

// A point of the head sphere, `radius_scale` x its radius out, at azimuth `az` (from the
// face towards the head's +X) and elevation `el` (radians) in the head's frame.
glm::vec3 on_head(const Head& head, float az, float el, float radius_scale) {
    const glm::vec3 local(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
    return head.centre + head.rotation * (radius_scale * head.radius * local);
}

// A filled oval on the head: half-widths `half_az` and `half_el` (radians) round (az, el),
// its points on the sphere 1% out.
void add_head_oval(DrawList& list, const Head& head, float az, float el, float half_az, float half_el) {
    constexpr int kSides = 16;
    constexpr float kOut = 1.01f;
    const glm::vec3 middle = on_head(head, az, el, kOut);
    for (int i = 0; i < kSides; ++i) {
        const float a0 = 6.28318530718f * static_cast<float>(i) / kSides, a1 = 6.28318530718f * static_cast<float>(i + 1) / kSides;
        list.add_unlit_triangle(middle, on_head(head, az + half_az * std::cos(a0), el + half_el * std::sin(a0), kOut),
                                on_head(head, az + half_az * std::cos(a1), el + half_el * std::sin(a1), kOut), kFaceColor);
    }
}

}  // namespace

std::optional<Head> head_of(const RodScene& scene, std::uint32_t c, std::span<const rods::Transform> joints) {
    const CharacterKinematics& k = scene.characters[scene.instances[c].character];
    const std::uint32_t reference = k.skeleton.reference;
    std::optional<Head> head;
    for (const ColliderAttachment& a : k.colliders) {
        if (a.joint != reference || a.kind != rods::ColliderKind::Outside || a.joint >= joints.size()) continue;
        if (glm::length(a.b - a.a) > 1e-6f) continue;  // a capsule
        if (head && head->radius >= a.radius) continue;
        const rods::Transform& j = joints[a.joint];
        head = Head{j.position + j.rotation * a.a, j.rotation, a.radius};
    }
    return head;
}

std::array<glm::vec3, 2> eye_centres(const Head& head) {
    const float az = glm::radians(kEyeAzimuthDeg), el = glm::radians(kEyeElevationDeg);
    return {on_head(head, az, el, 1.0f), on_head(head, -az, el, 1.0f)};
}

void add_face(DrawList& list, const Head& head) {
    const float az = glm::radians(kEyeAzimuthDeg), el = glm::radians(kEyeElevationDeg);
    // Tall ovals (an anime character's), 7 by 12 degrees of the sphere; a wide, thin mouth
    // 25 degrees below the middle.
    for (const float side : {1.0f, -1.0f}) add_head_oval(list, head, side * az, el, glm::radians(7.0f), glm::radians(12.0f));
    add_head_oval(list, head, 0.0f, glm::radians(-25.0f), glm::radians(8.0f), glm::radians(1.8f));
}

std::optional<Legs> legs_of(const RodScene& scene, std::uint32_t c, std::span<const rods::Transform> joints) {
    const CharacterInstance& inst = scene.instances[c];
    const CharacterKinematics& k = scene.characters[inst.character];
    if (k.rig || joints.empty()) return std::nullopt;
    const float floor = inst.placement.position.y;
    std::size_t lowest = 0;
    for (std::size_t j = 1; j < joints.size(); ++j) {
        if (joints[j].position.y < joints[lowest].position.y) lowest = j;
    }
    const rods::Transform& hips = joints[lowest];
    if (!(hips.position.y - floor > 0.1f)) return std::nullopt;
    Legs legs;
    // The feet point along the body's forward (+Z), made horizontal.
    const glm::vec3 forward = hips.rotation * glm::vec3(0.0f, 0.0f, 1.0f);
    const glm::vec2 flat(forward.x, forward.z);
    legs.forward = glm::length(flat) > 1e-4f ? glm::vec3(flat.x, 0.0f, flat.y) / glm::length(flat) : glm::vec3(0.0f, 0.0f, 1.0f);
    for (std::size_t s = 0; s < 2; ++s) {
        const float side = s == 0 ? 1.0f : -1.0f;
        legs.hip[s] = hips.position + hips.rotation * glm::vec3(side * kHipHalfWidth, 0.0f, 0.0f);
        legs.foot[s] = glm::vec3(legs.hip[s].x, floor, legs.hip[s].z);
    }
    return legs;
}

void add_legs(DrawList& list, const Legs& legs) {
    const glm::vec3 up(0.0f, kLegRadius, 0.0f);
    for (std::size_t s = 0; s < 2; ++s) {
        // The leg stops a radius above the floor, on the foot, whose underside is the floor.
        add_tube(list, legs.hip[s], legs.foot[s] + up, kLegRadius, kColliderColor);
        add_tube(list, legs.foot[s] + up - 0.3f * kFootLength * legs.forward, legs.foot[s] + up + 0.7f * kFootLength * legs.forward,
                 kLegRadius, kColliderColor);
    }
}

void add_characters(DrawList& list, const RodScene& scene, std::uint32_t frame) {
    std::vector<rods::Transform> joints, standing;
    for (std::uint32_t c = 0; c < scene.instances.size(); ++c) {
        scene.joint_poses(c, frame, joints);
        // Rigged characters with meshes are the renderer's skinned-mesh layer.
        const auto& rig = scene.characters[scene.instances[c].character].rig;
        const bool skinned = rig && draws_skinned(*rig);
        const std::optional<Legs> legs = skinned ? std::nullopt : legs_of(scene, c, joints);
        // The shadow of the whole figure, feet included.
        standing = joints;
        if (legs) {
            for (const glm::vec3& foot : legs->foot) standing.push_back({foot, glm::quat(1.0f, 0.0f, 0.0f, 0.0f)});
        }
        add_contact_shadow(list, standing);
        if (skinned) continue;
        const auto& parents = scene.joint_parents(c);
        for (std::size_t j = 0; j < joints.size() && j < parents.size(); ++j) {
            if (parents[j] < 0) continue;
            list.add_segment(joints[static_cast<std::size_t>(parents[j])].position, joints[j].position, 0.012f, 2.0f, kBoneColor);
        }
        if (const std::optional<Head> head = head_of(scene, c, joints)) add_face(list, *head);
        if (legs) add_legs(list, *legs);
    }
}

Perches perches_of(const birds::BirdWorld& world) {
    Perches out;
    const auto point = [&](std::uint32_t i) {
        const gpu::vec4& p = world.control_points[i];
        return glm::vec3(p.x, p.y, p.z);
    };
    // The birds by route, in one pass (a flock of a million birds has few routes).
    std::vector<std::vector<const gpu::BirdParams*>> by_route(world.routes.size());
    for (const gpu::BirdParams& b : world.birds) {
        if (b.ids.x < by_route.size()) by_route[b.ids.x].push_back(&b);
    }
    for (std::uint32_t r = 0; r < world.routes.size(); ++r) {
        const gpu::RouteHeader& route = world.routes[r];
        const std::uint32_t first = route.extent.x, segments = route.extent.y, last = first + 3 * segments;
        const std::vector<const gpu::BirdParams*>& birds = by_route[r];
        if (birds.empty() || segments == 0) continue;
        for (const bool takeoff : {true, false}) {
            if (!(route.flags.x & (takeoff ? KW_ROUTE_TAKEOFF : KW_ROUTE_LANDING))) continue;
            // A perched bird sits at the route's end point plus its offset, level, facing
            // along the route (engine/birds/flight.cpp).
            const glm::vec3 end = point(takeoff ? first : last);
            const glm::vec3 heading = takeoff ? point(first + 1) - end : end - point(last - 1);
            glm::vec3 across(heading.x, 0.0f, heading.z);
            across = glm::length(across) > 1e-6f ? glm::normalize(across) : glm::vec3(0.0f, 0.0f, 1.0f);
            const glm::vec3 along = glm::cross(glm::vec3(0.0f, 1.0f, 0.0f), across);
            float lo_along = 1e30f, hi_along = -1e30f, lo_across = 1e30f, hi_across = -1e30f, height = 0.0f;
            for (const gpu::BirdParams* b : birds) {
                const glm::vec3 belly = end + glm::vec3(b->offset.x, b->offset.y, b->offset.z) - glm::vec3(0.0f, kBellyDepth * b->shape.x, 0.0f);
                lo_along = std::min(lo_along, glm::dot(belly, along));
                hi_along = std::max(hi_along, glm::dot(belly, along));
                lo_across = std::min(lo_across, glm::dot(belly, across));
                hi_across = std::max(hi_across, glm::dot(belly, across));
                height += belly.y / static_cast<float>(birds.size());
            }
            // The ridge 1 m past the outermost birds; a flat top 0.2 m wider than the
            // birds' spread across it; eaves 3 m out from it.
            const float mid_across = 0.5f * (lo_across + hi_across);
            const auto at = [&](float s) { return s * along + mid_across * across + glm::vec3(0.0f, height, 0.0f); };
            Roof roof;
            roof.a = at(lo_along - 1.0f);
            roof.b = at(hi_along + 1.0f);
            roof.across = across;
            roof.cap = 0.5f * (hi_across - lo_across) + 0.2f;
            roof.half_depth = roof.cap + 3.0f;
            out.roofs.push_back(roof);
        }
        bool hovers = false;
        for (std::uint32_t s = 0; s < segments; ++s) hovers = hovers || world.control_points[first + 3 * s].w == static_cast<float>(KW_MODE_HOVER);
        if (hovers) {
            FlowerBed bed{glm::vec2(1e30f), glm::vec2(-1e30f)};
            float lowest = 1e30f;
            for (std::uint32_t i = first; i <= last; ++i) {
                for (const gpu::BirdParams* b : birds) {
                    const glm::vec3 p = point(i) + glm::vec3(b->offset.x, b->offset.y, b->offset.z);
                    bed.lo = glm::min(bed.lo, glm::vec2(p.x, p.z));
                    bed.hi = glm::max(bed.hi, glm::vec2(p.x, p.z));
                    lowest = std::min(lowest, p.y);
                }
            }
            bed.lo -= glm::vec2(1.0f);
            bed.hi += glm::vec2(1.0f);
            // Under 0.3 m a building would be a step: the bed lies on the ground.
            bed.height = lowest - kFlowerGap > 0.3f ? lowest - kFlowerGap : 0.0f;
            out.beds.push_back(bed);
        }
    }
    return out;
}

void add_perches(DrawList& list, const Perches& perches) {
    const glm::vec3 up(0.0f, 1.0f, 0.0f);
    for (const Roof& roof : perches.roofs) {
        const glm::vec3 w = roof.across;
        // Slopes of 35 degrees from the flat top's edges down to the eaves.
        const float drop = (roof.half_depth - roof.cap) * std::tan(glm::radians(35.0f));
        const glm::vec3 cap = roof.cap * w, eave = roof.half_depth * w - drop * up;
        add_quad(list, roof.a - cap, roof.b - cap, roof.b + cap, roof.a + cap, kRoofColor);
        add_quad(list, roof.a + cap, roof.b + cap, roof.b + eave, roof.a + eave, kRoofColor);
        const glm::vec3 back_eave = -roof.half_depth * w - drop * up;
        add_quad(list, roof.a + back_eave, roof.b + back_eave, roof.b - cap, roof.a - cap, kRoofColor);
        // The house: walls 0.4 m in from the roof's edges, from under the eaves to the
        // ground, and the gable ends up to the roof.
        const float eave_y = roof.a.y - drop;
        if (!(eave_y > 0.0f)) continue;
        const glm::vec3 along = glm::normalize(roof.b - roof.a);
        const glm::vec3 a = roof.a + 0.4f * along, b = roof.b - 0.4f * along;
        const float inset = roof.half_depth - 0.4f;
        const float top = eave_y + 0.4f * std::tan(glm::radians(35.0f));
        const auto ground = [&](glm::vec3 p) { return glm::vec3(p.x, 0.0f, p.z); };
        const auto level = [&](glm::vec3 p, float y) { return glm::vec3(p.x, y, p.z); };
        for (const float side : {1.0f, -1.0f}) {
            const glm::vec3 o = side * inset * w;
            add_quad(list, ground(a + o), ground(b + o), level(b + o, top), level(a + o, top), kWallColor);
        }
        for (const glm::vec3& end : {a, b}) {
            const glm::vec3 p = end + inset * w, q = end - inset * w;
            add_quad(list, ground(p), ground(q), level(q, top), level(p, top), kWallColor);
            // The gable: up to the roof's underside at this end.
            const float peak = roof.a.y - 0.05f;
            add_quad(list, level(p, top), level(q, top), level(end - roof.cap * w, peak), level(end + roof.cap * w, peak), kWallColor);
        }
    }
    // Flowers on a 0.5 m grid, each a stem and a blossom in one of four colours, picked by
    // a hash of its place so the bed looks the same every frame.
    constexpr std::array<Rgba8, 4> kBlossoms{Rgba8{225, 70, 120}, Rgba8{245, 200, 40}, Rgba8{200, 40, 40}, Rgba8{150, 90, 210}};
    constexpr Rgba8 kStem{60, 120, 50};
    for (const FlowerBed& bed : perches.beds) {
        // On the ground, just over the grid lines.
        const float kLift = bed.height > 0.0f ? bed.height : 0.005f;
        add_quad(list, {bed.lo.x, kLift, bed.lo.y}, {bed.lo.x, kLift, bed.hi.y}, {bed.hi.x, kLift, bed.hi.y}, {bed.hi.x, kLift, bed.lo.y},
                 kSoilColor);
        if (bed.height > 0.0f) {
            // The building under a roof garden: four walls from the ground to the soil.
            const glm::vec3 c[4] = {{bed.lo.x, 0.0f, bed.lo.y}, {bed.hi.x, 0.0f, bed.lo.y}, {bed.hi.x, 0.0f, bed.hi.y}, {bed.lo.x, 0.0f, bed.hi.y}};
            for (int k = 0; k < 4; ++k) {
                const glm::vec3 p = c[k], q = c[(k + 1) % 4];
                add_quad(list, p, q, q + glm::vec3(0.0f, bed.height, 0.0f), p + glm::vec3(0.0f, bed.height, 0.0f), kWallColor);
            }
        }
        const int nx = static_cast<int>((bed.hi.x - bed.lo.x) / 0.5f), nz = static_cast<int>((bed.hi.y - bed.lo.y) / 0.5f);
        for (int i = 0; i < nx; ++i) {
            for (int j = 0; j < nz; ++j) {
                const std::uint32_t hash = (static_cast<std::uint32_t>(i) * 73856093u) ^ (static_cast<std::uint32_t>(j) * 19349663u);
                const float jitter_x = static_cast<float>(hash % 97u) / 97.0f - 0.5f, jitter_z = static_cast<float>((hash / 97u) % 89u) / 89.0f - 0.5f;
                const glm::vec3 base(bed.lo.x + 0.5f * (static_cast<float>(i) + 0.5f + 0.6f * jitter_x), kLift,
                                     bed.lo.y + 0.5f * (static_cast<float>(j) + 0.5f + 0.6f * jitter_z));
                const glm::vec3 blossom = base + glm::vec3(0.0f, 0.35f + 0.15f * jitter_x, 0.0f);
                list.add_segment(base, blossom, 0.02f, 1.0f, kStem);
                list.add_dot(blossom, 0.08f, 1.5f, kBlossoms[(hash >> 7) % kBlossoms.size()]);
            }
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

}  // namespace kodawari
