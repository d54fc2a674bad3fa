// Levels of detail (kodawari/rods/lod.hpp): the settings' checks, the camera's part of the
// decision, and the decision itself from the one definition that rods_step.comp compiles
// too (shaders/lib/rod_lod.glsl).
#include "kodawari/rods/lod.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "kodawari/shared/rods.h"

namespace kodawari::rods {

static_assert(static_cast<std::uint32_t>(Level::Full) == KW_RODS_LEVEL_FULL);
static_assert(static_cast<std::uint32_t>(Level::Posed) == KW_RODS_LEVEL_POSED);
static_assert(static_cast<std::uint32_t>(Level::Hidden) == KW_RODS_LEVEL_HIDDEN);
static_assert(static_cast<std::uint32_t>(Level::Reduced) == KW_RODS_LEVEL_REDUCED);
// RodChainStateGpu.view.w keeps a level below KW_RODS_IDLE_UNIT beside its idle frames.
static_assert(KW_RODS_LEVEL_REDUCED < KW_RODS_IDLE_UNIT);

static_assert(kPosedPeriod == KW_RODS_POSED_PERIOD && kHiddenPeriod == KW_RODS_HIDDEN_PERIOD && kRateGroup == KW_RODS_RATE_GROUP);
// rod_rests() takes a turn modulo the period: powers of two that divide 4 (RodPush.flags.w
// carries the frame's turn mod 4).
static_assert(4 % kPosedPeriod == 0 && 4 % kHiddenPeriod == 0);
// rod_far_off_view()'s widening: KW_RODS_FAR_OFF_TAN is tan(KW_RODS_FAR_OFF_DEG degrees).
static_assert(KW_RODS_FAR_OFF_TAN > 0.36397f && KW_RODS_FAR_OFF_TAN < 0.36398f && KW_RODS_FAR_OFF_DEG == 20);

namespace glsl {
// GLSL's names for shaders/lib/rod_lod.glsl (inside this namespace only).
using uint = std::uint32_t;
#define KW_LOD_FN inline
#include "lib/rod_lod.glsl"
#undef KW_LOD_FN
}  // namespace glsl

Result<void> validate(const LodSettings& lod, const char* what) {
    auto bad = [&](const std::string& field, const std::string& expected) {
        return make_error(Error::Kind::InvalidInput, std::string(what) + "." + field + ": expected " + expected);
    };
    if (!(lod.size > 0.0f && lod.size <= 1000.0f)) return bad("size", "a number in (0, 1000] m");
    if (!(lod.full_pixels > 0.0f && lod.full_pixels <= 100000.0f)) return bad("full_pixels", "a number in (0, 100000] pixels");
    if (!(lod.reduced_pixels == 0.0f || (lod.reduced_pixels > 0.0f && lod.reduced_pixels < lod.full_pixels))) {
        return bad("reduced_pixels", "0 (no reduced level) or a number of pixels in (0, full_pixels)");
    }
    if (!(lod.hysteresis >= 0.0f && lod.hysteresis <= 0.9f)) return bad("hysteresis", "a number in [0, 0.9]");
    if (!(lod.bias >= -8.0f && lod.bias <= 8.0f)) return bad("bias", "a number in [-8, 8]");
    if (!(lod.settle_rate > 0.0f && lod.settle_rate <= 1000.0f)) return bad("settle_rate", "a number in (0, 1000] 1/s");
    if (!(lod.blend_time > 0.0f && lod.blend_time <= 100.0f)) return bad("blend_time", "a number in (0, 100] s");
    if (!(lod.vertical_fov_deg > 0.0f && lod.vertical_fov_deg < 180.0f)) return bad("vertical_fov_deg", "a number in (0, 180) degrees");
    if (!(lod.aspect > 0.0f && lod.aspect <= 100.0f)) return bad("aspect", "a number in (0, 100]");
    if (!(lod.budget_ms == 0.0f || (lod.budget_ms > 0.0f && lod.budget_ms <= 100000.0f))) {
        return bad("budget_ms", "0 (no budget) or a number of milliseconds in (0, 100000]");
    }
    KW_TRY(validate(lod.costs, (std::string(what) + ".costs").c_str()));
    if (!(lod.viewport_height >= 1.0f && lod.viewport_height <= 100000.0f)) return bad("viewport_height", "a number in [1, 100000] pixels");
    return {};
}

LodView lod_view(const LodSettings& lod, const Camera& camera, float cap) {
    LodView v;
    v.enabled = lod.enabled && camera.projection == Camera::Projection::Perspective;
    if (!v.enabled) return v;
    v.position = camera.position;
    v.forward = camera.forward;
    // The camera's right and up with +Y up, as every view of Kodawari renders it; a camera
    // looking straight up or down takes +X as its right.
    const glm::vec3 side = glm::cross(v.forward, glm::vec3(0.0f, 1.0f, 0.0f));
    const float side_length = glm::length(side);
    v.right = side_length > 1e-6f ? side / side_length : glm::vec3(1.0f, 0.0f, 0.0f);
    v.up = glm::cross(v.right, v.forward);
    v.tan_y = std::tan(glm::radians(lod.vertical_fov_deg) * 0.5f);
    v.tan_x = v.tan_y * lod.aspect;
    v.margin = lod.size;
    v.lower_rate = lod.lower_rate;
    // The size's projection in pixels at depth z: size x viewport_height / (2 tan_y z) x
    // 2^bias; it reaches full_pixels at z = that scale / full_pixels.
    const float scale = lod.size * lod.viewport_height / (2.0f * v.tan_y) * std::exp2(lod.bias);
    v.full_distance = scale / lod.full_pixels;
    v.stay_distance = scale / (lod.full_pixels * (1.0f - lod.hysteresis));
    // The reduced level's band beyond (lod.reduced_pixels; the full one's distances when off).
    v.reduced_distance = lod.reduced_pixels > 0.0f ? scale / lod.reduced_pixels : v.full_distance;
    v.reduced_stay = lod.reduced_pixels > 0.0f ? scale / (lod.reduced_pixels * (1.0f - lod.hysteresis)) : v.stay_distance;
    // The budget's cap: no character deeper is full or reduced, and the hysteresis bands
    // end there too (a simulated one past it would spend what the budget gave a nearer one).
    if (cap < v.full_distance) v.full_distance = cap;
    if (cap < v.stay_distance) v.stay_distance = std::max(cap, v.full_distance);
    if (cap < v.reduced_distance) v.reduced_distance = cap;
    if (cap < v.reduced_stay) v.reduced_stay = std::max(cap, v.reduced_distance);
    return v;
}

Level chain_level(const LodView& view, glm::vec3 reference, Level previous) {
    if (!view.enabled) return Level::Full;
    const glm::vec3 offset = reference - view.position;
    return static_cast<Level>(glsl::rod_level(glm::dot(offset, view.forward), glm::dot(offset, view.right),
                                              glm::dot(offset, view.up), view.tan_x, view.tan_y, view.margin,
                                              view.full_distance, view.stay_distance, view.reduced_distance,
                                              view.reduced_stay, static_cast<std::uint32_t>(previous)));
}

bool chain_rests(const LodView& view, glm::vec3 reference, Level level, Level previous, std::uint32_t turn) {
    if (!view.enabled || !view.lower_rate) return false;
    const glm::vec3 offset = reference - view.position;
    const float depth = glm::dot(offset, view.forward);
    const bool far_off = level == Level::Hidden && glsl::rod_far_off_view(depth, glm::dot(offset, view.right),
                                                                          glm::dot(offset, view.up), view.tan_x,
                                                                          view.tan_y, view.margin);
    return glsl::rod_rests(static_cast<std::uint32_t>(level), static_cast<std::uint32_t>(previous), depth,
                           view.reduced_distance, far_off, turn);
}

SolverParams reduced_params(const SolverParams& params) {
    SolverParams reduced = params;
    reduced.max_substep = std::min(0.05f, 2.0f * params.max_substep);  // validate()'s longest
    reduced.iterations = std::max(1u, (params.iterations + 1u) / 2u);
    return reduced;
}

float posed_blend(const LodSettings& lod, float dt) { return 1.0f - std::exp(-lod.settle_rate * dt); }

float blend_in(const LodSettings& lod, Level level, float previous, float dt) {
    if (!dynamic(level)) return 0.0f;
    return std::min(1.0f, previous + dt / lod.blend_time);
}

}  // namespace kodawari::rods
