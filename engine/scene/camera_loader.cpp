// The moving camera of a version-2 scene (docs/scene-format.md, "Moving camera"): projection, orbit, path and keyframes.
#include "scene/character_loader.hpp"

#include <cmath>
#include <numbers>
#include <string>
#include <string_view>

namespace kodawari::scene_detail {

constexpr std::size_t kMaxCameraKeys = 4096;

using Vec3 = glm::vec3;

Result<std::size_t> read_interpolation(const JsonReader& r, const JsonNode& node, rods::Interpolation& out) {
    std::size_t value = 0;
    KW_SCENE_ASSIGN(value, r.choice(node, {"catmull-rom", "linear"}));
    out = value == 0 ? rods::Interpolation::CatmullRom : rods::Interpolation::Linear;
    return value;
}

Result<void> read_orbit(const JsonReader& r, const JsonNode& node, rods::CameraMotion& m) {
    KW_TRY(r.object(node, {"target", "radius", "height", "degrees_per_second", "period", "start_deg"}));
    m.kind = rods::CameraMotion::Kind::Orbit;
    KW_SCENE_ASSIGN(m.target, read_point(r, r.member(node, "target"), kMaxCoordinate / 2));
    KW_SCENE_ASSIGN(m.radius, r.real(r.member(node, "radius"), NumberRange::left_open(0.0, kMaxCoordinate / 2)));
    KW_TRY(optional_member(r, node, "height", m.height,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(-kMaxCoordinate / 2, kMaxCoordinate / 2)); }));
    const JsonNode rate = r.member(node, "degrees_per_second");
    const JsonNode period = r.member(node, "period");
    if (rate.present() && period.present()) {
        return r.fail(period.path, "expected at most one of \"degrees_per_second\" and \"period\", got both");
    }
    m.rate = static_cast<float>(30.0 * kDegToRad);
    if (rate.present()) KW_SCENE_ASSIGN(m.rate, read_degrees(r, rate, NumberRange::closed(-36000.0, 36000.0)));
    if (period.present()) {
        double seconds = 0.0;
        KW_SCENE_ASSIGN(seconds, r.number(period, NumberRange::left_open(0.0, kMaxTime)));
        m.rate = static_cast<float>(2.0 * std::numbers::pi / seconds);
    }
    KW_TRY(optional_member(r, node, "start_deg", m.start_angle,
                           [&](const JsonNode& n) { return read_degrees(r, n, NumberRange::closed(-3600.0, 3600.0)); }));
    return {};
}

Result<void> read_path(const JsonReader& r, const JsonNode& node, rods::CameraMotion& m) {
    KW_TRY(r.object(node, {"points", "target", "segment_duration", "interpolation", "loop"}));
    m.kind = rods::CameraMotion::Kind::Keyframes;
    Vec3 target{};
    KW_SCENE_ASSIGN(target, read_point(r, r.member(node, "target"), kMaxCoordinate));
    float segment = 1.0f;
    KW_TRY(optional_member(r, node, "segment_duration", segment,  // >= 1 ms: time / segment finite
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.001, 3600.0)); }));
    const JsonNode interpolation = r.member(node, "interpolation");
    if (interpolation.present()) KW_TRY(read_interpolation(r, interpolation, m.interpolation));
    KW_TRY(optional_member(r, node, "loop", m.loop, [&](const JsonNode& n) { return r.boolean(n); }));
    const JsonNode points = r.member(node, "points");
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, points, 2, kMaxCameraKeys - 1,
                                  "an array of 2 to " + std::to_string(kMaxCameraKeys - 1) + " points [x, y, z]"));
    for (std::size_t i = 0; i < n; ++i) {
        const JsonNode p = r.element(points, i);
        rods::CameraKey key;
        KW_SCENE_ASSIGN(key.position, read_point(r, p, kMaxCoordinate));
        if (key.position == target) return r.expected(p, "a point other than the path's target (the camera needs a direction)");
        key.time = static_cast<float>(static_cast<double>(segment) * static_cast<double>(i));
        key.target = target;
        m.keys.push_back(key);
    }
    if (m.loop) {
        rods::CameraKey close = m.keys.front();
        close.time = static_cast<float>(static_cast<double>(segment) * static_cast<double>(n));
        m.keys.push_back(close);
    }
    return {};
}

Result<void> read_keyframes(const JsonReader& r, const JsonNode& node, rods::CameraMotion& m) {
    KW_TRY(r.object(node, {"keys", "interpolation", "loop"}));
    m.kind = rods::CameraMotion::Kind::Keyframes;
    const JsonNode interpolation = r.member(node, "interpolation");
    if (interpolation.present()) KW_TRY(read_interpolation(r, interpolation, m.interpolation));
    KW_TRY(optional_member(r, node, "loop", m.loop, [&](const JsonNode& n) { return r.boolean(n); }));
    const JsonNode keys = r.member(node, "keys");
    std::size_t n = 0;
    KW_SCENE_ASSIGN(n, read_array(r, keys, m.loop ? 2 : 1, kMaxCameraKeys,
                                  "an array of " + std::string(m.loop ? "2" : "1") + " to " + std::to_string(kMaxCameraKeys) +
                                      " keys {\"time\", \"position\", \"target\"}"));
    for (std::size_t i = 0; i < n; ++i) {
        const JsonNode k = r.element(keys, i);
        KW_TRY(r.object(k, {"time", "position", "target"}));
        rods::CameraKey key;
        const JsonNode time = r.member(k, "time");
        KW_SCENE_ASSIGN(key.time, read_time(r, time));
        if (i > 0 && !(key.time > m.keys.back().time)) {
            return r.expected(time, "a time after the previous key's (" + format_number(m.keys.back().time) + " s)");
        }
        KW_SCENE_ASSIGN(key.position, read_point(r, r.member(k, "position"), kMaxCoordinate));
        KW_SCENE_ASSIGN(key.target, read_point(r, r.member(k, "target"), kMaxCoordinate));
        if (key.target == key.position) {
            return r.expected(r.member(k, "target"), "a point other than the key's position (the camera needs a direction)");
        }
        m.keys.push_back(key);
    }
    if (m.loop && (m.keys.back().position != m.keys.front().position || m.keys.back().target != m.keys.front().target)) {
        return r.expected(r.element(keys, n - 1), "the same position and target as keys[0] (a looping camera ends where it starts)");
    }
    return {};
}

Result<void> read_camera_motion(const JsonReader& r, const JsonNode& node, CameraSpec& camera) {
    rods::CameraMotion& m = camera.motion;
    m.kind = rods::CameraMotion::Kind::Fixed;
    m.position = to_vec(camera.position);
    m.target = to_vec(camera.target);
    const JsonNode projection = r.member(node, "projection");
    if (projection.present()) {
        std::size_t value = 0;
        KW_SCENE_ASSIGN(value, r.choice(projection, {"perspective", "orthographic"}));
        m.projection = value == 0 ? rods::Camera::Projection::Perspective : rods::Camera::Projection::Orthographic;
    }
    const char* moving = nullptr;
    for (const char* key : {"orbit", "path", "keyframes"}) {
        const JsonNode n = r.member(node, key);
        if (!n.present()) continue;
        if (moving != nullptr) {
            return r.fail(n.path, std::string("expected at most one of \"orbit\", \"path\" and \"keyframes\", got \"") + moving +
                                      "\" and \"" + key + "\"");
        }
        moving = key;
    }
    if (moving == nullptr) return {};
    for (const char* fixed : {"position", "target"}) {
        const JsonNode n = r.member(node, fixed);
        if (n.present()) {
            return r.fail(n.path, std::string("not used with \"") + moving + "\" (it places and aims the camera itself)");
        }
    }
    const JsonNode n = r.member(node, moving);
    if (std::string_view(moving) == "orbit") return read_orbit(r, n, m);
    if (std::string_view(moving) == "path") return read_path(r, n, m);
    return read_keyframes(r, n, m);
}

}  // namespace kodawari::scene_detail
