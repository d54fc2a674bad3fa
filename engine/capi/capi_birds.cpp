// The C API's bird worlds (SPEC B): a birds::BirdWorld built from the caller's routes and
// flocks, a bird backend that flies it, and the poses turned into part transforms (each
// part relative to its parent, or in world space). Arguments are checked before anything
// changes; BirdWorld::add_route's checks (finite points, no coincident points, no cusp)
// name the route by its argument path.
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "capi/capi_bird_pose.hpp"
#include "capi/capi_common.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/birds/rig.hpp"
#include "kodawari/birds/world.hpp"

using namespace kodawari;
using namespace kodawari::capi;

namespace {

constexpr std::uint64_t kMaxBirds = 10'000'000;     // as the scene files
constexpr std::uint32_t kMaxFramesPerCall = 100'000;
constexpr double kMaxOffset = 1e4;                 // m, as the scene files' formation spread
constexpr double kMaxTimeOffset = 3600.0;          // s, as the scene files' trail
constexpr double kDegree = std::numbers::pi / 180.0;

}  // namespace

/// The opaque handle of kodawari.h.
struct kodawari_bird_world {
    std::string message;  // the last call's (kodawari_bird_world_last_error)
    birds::BirdWorld world;
    std::unique_ptr<BirdBackend> backend;
    BackendKind kind = BackendKind::CpuReference;
    std::string fallback_reason;
    std::uint32_t next_frame = 0;
    std::vector<gpu::BirdPose> poses;  // simulate()'s scratch, reused
    std::array<PartOffsets, birds::kWingTypeCount> offsets{};
};

namespace {

// The C enum and the engine's are one numbering: a value is passed through as it is.
static_assert(KODAWARI_WING_PIGEON == static_cast<int>(birds::WingType::Pigeon) &&
                  KODAWARI_WING_GULL == static_cast<int>(birds::WingType::Gull) &&
                  KODAWARI_WING_HAWK == static_cast<int>(birds::WingType::Hawk) &&
                  KODAWARI_WING_HUMMINGBIRD == static_cast<int>(birds::WingType::Hummingbird) &&
                  KODAWARI_WING_STARLING == static_cast<int>(birds::WingType::Starling),
              "kodawari_wing_type and birds::WingType number the wing types alike");

birds::WingType read_wing_type(kodawari_wing_type type, const std::string& what) {
    const std::int64_t value = enum_value(type);
    if (value < 0 || value >= static_cast<std::int64_t>(birds::kWingTypeCount)) {
        static_assert(birds::kWingTypeCount == 5, "the message lists every wing type");
        invalid(what, std::to_string(value) + "; expected KODAWARI_WING_PIGEON (0), _GULL (1), _HAWK (2), _HUMMINGBIRD (3) or _STARLING (4)");
    }
    return static_cast<birds::WingType>(value);
}

birds::FlightSettings read_flight(const kodawari_flight_settings& f, const std::string& what) {
    require_range(f.gravity, 0.0, 1000.0, what + ".gravity", true);
    require_range(f.max_bank, 0.0, 89.0 * kDegree, what + ".max_bank");
    require_flag(f.seed_bank_rule, what + ".seed_bank_rule");
    require_flag(f.seed_mode_rule, what + ".seed_mode_rule");
    const float* thresholds[] = {&f.ascend_enter, &f.ascend_exit, &f.descend_enter, &f.descend_exit};
    const char* names[] = {".ascend_enter", ".ascend_exit", ".descend_enter", ".descend_exit"};
    for (std::size_t i = 0; i < 4; ++i) require_range(*thresholds[i], -90.0 * kDegree, 90.0 * kDegree, what + names[i], true, true);
    // Nested, so that the hysteresis works (SPEC B.5; the scene files' rule).
    if (!(f.ascend_exit < f.ascend_enter)) {
        invalid(what + ".ascend_exit", number(f.ascend_exit) + "; expected below ascend_enter (" + number(f.ascend_enter) + ")");
    }
    if (!(f.descend_enter < f.descend_exit)) {
        invalid(what + ".descend_enter",
                number(f.descend_enter) + "; expected below descend_exit (" + number(f.descend_exit) + ")");
    }
    if (!(f.descend_exit <= f.ascend_exit)) {
        invalid(what + ".descend_exit",
                number(f.descend_exit) + "; expected at or below ascend_exit (" + number(f.ascend_exit) + ")");
    }
    require_range(f.seed_accel_threshold, 0.0, 1000.0, what + ".seed_accel_threshold", true);
    for (std::size_t i = 0; i < 3; ++i) require_range(f.blend_rates[i], 0.0, 1.0, at(what + ".blend_rates", i), true);
    require_range(f.bank_time_constant, 0.0, 10.0, what + ".bank_time_constant");
    birds::FlightSettings s;
    s.gravity = f.gravity;
    s.max_bank = f.max_bank;
    s.bank_rule = f.seed_bank_rule ? birds::BankRule::Seed : birds::BankRule::Coordinated;
    s.mode_rule = f.seed_mode_rule ? birds::ModeRule::Seed : birds::ModeRule::Climb;
    s.ascend_enter = f.ascend_enter;
    s.ascend_exit = f.ascend_exit;
    s.descend_enter = f.descend_enter;
    s.descend_exit = f.descend_exit;
    s.seed_accel_threshold = f.seed_accel_threshold;
    s.blend_rates = {f.blend_rates[0], f.blend_rates[1], f.blend_rates[2]};
    s.bank_time = f.bank_time_constant;
    return s;
}

void read_route(const kodawari_route_desc& r, const std::string& what, birds::BirdWorld& world) {
    if (r.point_count < 4 || (r.point_count - 1) % 3 != 0) {
        invalid(what + ".point_count", std::to_string(r.point_count) +
                                           "; expected 3n + 1 control points (n >= 1 cubic Bezier segments): 4, 7, 10, ...");
    }
    require_pointer(r.points, what + ".points");
    require_flag(r.loop, what + ".loop");
    require_flag(r.parametric, what + ".parametric");
    if (r.parametric) require_range(r.segment_duration, 0.001, 3600.0, what + ".segment_duration");  // t / it finite
    birds::RouteSpec spec;
    spec.points.resize(r.point_count);
    for (std::uint32_t i = 0; i < r.point_count; ++i) spec.points[i] = {r.points[3 * i], r.points[3 * i + 1], r.points[3 * i + 2]};
    spec.loop = r.loop != 0;
    spec.timing = r.parametric ? birds::RouteTiming::Parametric : birds::RouteTiming::ArcLength;
    if (r.parametric) spec.segment_duration = r.segment_duration;
    if (r.modes != nullptr) {
        const std::uint32_t segments = (r.point_count - 1) / 3;
        spec.modes.resize(segments);
        for (std::uint32_t k = 0; k < segments; ++k) {
            const std::int32_t m = r.modes[k];
            if (m != KODAWARI_SEGMENT_AUTO && (m < KODAWARI_SEGMENT_GLIDE || m > KODAWARI_SEGMENT_HOVER)) {
                invalid(at(what + ".modes", k), std::to_string(m) + "; expected a kodawari_segment_mode (-1, or 3 to 6)");
            }
            spec.modes[k] = static_cast<birds::SegmentMode>(m);
        }
    }
    // Segment modes where they may stand, finite points within 1e6 m, loops closed, no coincident points, no cusp; its
    // messages start with `what`.
    check(world.add_route(spec, what));
}

void read_flock(const kodawari_flock_desc& f, const std::string& what, std::uint32_t routes, std::uint64_t& total,
                birds::BirdWorld& world) {
    if (f.route >= routes) {
        invalid(what + ".route", std::to_string(f.route) + "; expected an index below desc->route_count (" +
                                     std::to_string(routes) + ")");
    }
    const birds::WingType wing = read_wing_type(f.wing_type, what + ".wing_type");
    if (!birds::wing_type_spec(wing).can_hover) {
        // A hover segment's mode is in the w of its first control point (shared/birds.h).
        const gpu::RouteHeader& route = world.routes[f.route];
        for (std::uint32_t k = 0; k < route.extent.y; ++k) {
            if (world.control_points[route.extent.x + 3 * k].w == static_cast<float>(KW_MODE_HOVER)) {
                invalid(what + ".wing_type", std::string(birds::wing_type_spec(wing).name) + " cannot hover, but its route's segment " +
                                                 std::to_string(k) + " is KODAWARI_SEGMENT_HOVER");
            }
        }
    }
    if (f.count == 0) invalid(what + ".count", "0; expected at least one bird");
    total += f.count;
    if (total > kMaxBirds) {
        invalid(what + ".count", std::to_string(f.count) + " makes " + std::to_string(total) + " birds; expected at most " +
                                     std::to_string(kMaxBirds) + " in a world");
    }
    require_range(f.speed, 0.0, 1000.0, what + ".speed", true);
    require_range(f.frequency, 0.0, 1000.0, what + ".frequency", true);
    require_range(f.amplitude, 0.0, 3.0, what + ".amplitude", true);
    for (std::uint32_t b = 0; f.offsets != nullptr && b < f.count; ++b) {
        const float* o = f.offsets + 4 * b;
        const std::string bird = at(what + ".offsets", b);
        require_point(o, kMaxOffset, bird + " (x, y, z)");
        require_range(o[3], 0.0, kMaxTimeOffset, bird + " (w, the time offset in s)");
    }
    for (std::uint32_t b = 0; f.phases != nullptr && b < f.count; ++b) {
        require_range(f.phases[b], 0.0, 1.0, at(what + ".phases", b), false, true);
    }
    for (std::uint32_t b = 0; b < f.count; ++b) {
        gpu::BirdParams p{};
        if (f.offsets != nullptr) p.offset = {f.offsets[4 * b], f.offsets[4 * b + 1], f.offsets[4 * b + 2], f.offsets[4 * b + 3]};
        // Without phases, spread evenly so that neighbours do not beat in step; in double so
        // that b / count is rounded once (and stays below 1).
        float phase = f.phases != nullptr ? f.phases[b] : static_cast<float>(static_cast<double>(b) / f.count);
        if (phase >= 1.0f) phase = 0.0f;  // b / count just below 1 can round up to 1.0f: phase 0 of the next cycle
        p.motion = {f.speed, f.frequency, f.amplitude, phase};
        p.ids = {f.route, static_cast<std::uint32_t>(wing), 0u, 0u};
        p.flight = birds::flight_params(birds::wing_type_spec(wing));
        p.shape = birds::shape_params(birds::wing_type_spec(wing));
        world.birds.push_back(p);
    }
}

void read_world(const kodawari_bird_world_desc& desc, birds::BirdWorld& world) {
    if (desc.route_count == 0) invalid("desc->route_count", "0; expected at least one route");
    require_array(desc.routes, desc.route_count, "desc->routes", "desc->route_count");
    if (desc.flock_count == 0) invalid("desc->flock_count", "0; expected at least one flock");
    require_array(desc.flocks, desc.flock_count, "desc->flocks", "desc->flock_count");
    require_range(desc.fps, 0.01, 1000.0, "desc->fps");  // f / fps finite for any f
    world.fps = desc.fps;
    // The vulkan backend sizes its ring of output frames by this (bounded by its own byte
    // budget); the C API does not know how many frames a caller asks for at once.
    world.frames = 256;
    world.settings = read_flight(desc.flight, "desc->flight");
    for (std::uint32_t i = 0; i < desc.route_count; ++i) read_route(desc.routes[i], at("desc->routes", i), world);
    std::uint64_t total = 0;
    for (std::uint32_t i = 0; i < desc.flock_count; ++i) {
        read_flock(desc.flocks[i], at("desc->flocks", i), desc.route_count, total, world);
    }
}

void open_and_load(kodawari_bird_world& w, const kodawari_backend_options& options) {
    w.backend = capi::open_and_load<BirdBackend>(options, w.kind, w.fallback_reason, make_bird_backend,
                                               [&](BirdBackend& backend) { return backend.load(w.world); });
}

void require_world(const kodawari_bird_world* world) { require_pointer(world, "world"); }

}  // namespace

extern "C" {

KODAWARI_C_API kodawari_status kodawari_flock_desc_default(kodawari_wing_type wing_type, uint32_t count,
                                                           kodawari_flock_desc* out) {
    return guard("kodawari_flock_desc_default", nullptr, [&] {
        const birds::WingType wing = read_wing_type(wing_type, "wing_type");
        require_pointer(out, "out");
        const birds::WingTypeSpec& spec = birds::wing_type_spec(wing);
        kodawari_flock_desc f{};
        f.route = 0;
        f.wing_type = wing_type;
        f.count = count;
        f.speed = spec.cruise_speed;
        f.frequency = spec.flap_frequency;
        f.amplitude = spec.amplitude;
        *out = f;
    });
}

KODAWARI_C_API kodawari_status kodawari_flight_settings_default(kodawari_flight_settings* out) {
    return guard("kodawari_flight_settings_default", nullptr, [&] {
        require_pointer(out, "out");
        const birds::FlightSettings s;
        kodawari_flight_settings f{};
        f.gravity = s.gravity;
        f.max_bank = s.max_bank;
        f.seed_bank_rule = s.bank_rule == birds::BankRule::Seed ? 1u : 0u;
        f.seed_mode_rule = s.mode_rule == birds::ModeRule::Seed ? 1u : 0u;
        f.ascend_enter = s.ascend_enter;
        f.ascend_exit = s.ascend_exit;
        f.descend_enter = s.descend_enter;
        f.descend_exit = s.descend_exit;
        f.seed_accel_threshold = s.seed_accel_threshold;
        for (std::size_t i = 0; i < 3; ++i) f.blend_rates[i] = s.blend_rates[i];
        f.bank_time_constant = s.bank_time;
        *out = f;
    });
}

KODAWARI_C_API kodawari_status kodawari_bird_world_create(const kodawari_bird_world_desc* desc, kodawari_bird_world** out) {
    return guard("kodawari_bird_world_create", nullptr, [&] {
        require_pointer(out, "out");
        *out = nullptr;
        require_pointer(desc, "desc");
        require_backend_options(desc->backend, "desc->backend");
        auto w = std::make_unique<kodawari_bird_world>();
        read_world(*desc, w->world);
        w->offsets = all_part_offsets();
        open_and_load(*w, desc->backend);
        *out = w.release();
    });
}

KODAWARI_C_API void kodawari_bird_world_destroy(kodawari_bird_world* world) { delete world; }

KODAWARI_C_API const char* kodawari_bird_world_last_error(const kodawari_bird_world* world) {
    return world != nullptr ? world->message.c_str() : "";
}

KODAWARI_C_API kodawari_status kodawari_bird_world_rewind(kodawari_bird_world* world) {
    return guard("kodawari_bird_world_rewind", world ? &world->message : nullptr, [&] {
        require_world(world);
        check(world->backend->load(world->world));
        world->next_frame = 0;
    });
}

KODAWARI_C_API kodawari_status kodawari_bird_world_record_simulate(kodawari_bird_world* world, void* command_buffer,
                                                                   uint32_t frames) {
    return guard("kodawari_bird_world_record_simulate", world ? &world->message : nullptr, [&] {
        require_world(world);
        require_pointer(command_buffer, "command_buffer");
        if (world->kind != BackendKind::Vulkan) {
            invalid("world", "runs on the " + std::string(world->backend->name()) +
                                 " backend; recording needs a vulkan world (backend options with vulkan_device)");
        }
        if (frames > std::numeric_limits<std::uint32_t>::max() - world->next_frame) {
            invalid("frames", std::to_string(frames) + " frames after frame " + std::to_string(world->next_frame) +
                                  " pass the last frame a world counts; rewind first");
        }
        check(record_simulate(*world->backend, static_cast<VkCommandBuffer>(command_buffer), frames));
        world->next_frame += frames;
    });
}

KODAWARI_C_API kodawari_status kodawari_bird_world_buffer(kodawari_bird_world* world, kodawari_device_buffer which,
                                                          kodawari_buffer_range* out) {
    return guard("kodawari_bird_world_buffer", world ? &world->message : nullptr, [&] {
        require_world(world);
        fill_range(world->backend->device_data(), which, out, false);
    });
}

KODAWARI_C_API kodawari_status kodawari_bird_world_simulate(kodawari_bird_world* world, uint32_t frames,
                                                            const kodawari_bird_output* out) {
    return guard("kodawari_bird_world_simulate", world ? &world->message : nullptr, [&] {
        require_world(world);
        if (frames < 1 || frames > kMaxFramesPerCall) {
            invalid("frames", std::to_string(frames) + "; expected 1 to " + std::to_string(kMaxFramesPerCall));
        }
        if (frames > std::numeric_limits<std::uint32_t>::max() - world->next_frame) {
            invalid("frames", std::to_string(frames) + " frames after frame " + std::to_string(world->next_frame) +
                                  " pass the last frame a world counts; rewind first");
        }
        const std::size_t birds = world->world.birds.size();
        const std::size_t needed = std::size_t{frames} * birds * kFloatsPerBird;
        const std::string why = std::to_string(frames) + " frames x " + std::to_string(birds) + " birds x " +
                                std::to_string(KODAWARI_BIRD_PARTS) + " parts x " + std::to_string(KODAWARI_TRANSFORM_FLOATS);
        float* local = nullptr;
        float* global = nullptr;
        if (out != nullptr) {
            require_capacity(out->local_transforms, out->local_transforms_capacity, needed, "out->local_transforms", why);
            require_capacity(out->world_transforms, out->world_transforms_capacity, needed, "out->world_transforms", why);
            local = out->local_transforms;
            global = out->world_transforms;
        }
        if (local == nullptr && global == nullptr) {
            check(world->backend->simulate(frames, FrameOutput{}));
            world->next_frame += frames;
            return;
        }
        world->poses.resize(std::size_t{frames} * birds);
        check(world->backend->simulate(frames, FrameOutput{world->poses, {}}));
        world->next_frame += frames;
        for (std::size_t i = 0; i < world->poses.size(); ++i) {
            const std::uint32_t wing = world->world.birds[i % birds].ids.y;
            part_transforms(world->poses[i], world->offsets[wing], local ? local + i * kFloatsPerBird : nullptr,
                            global ? global + i * kFloatsPerBird : nullptr);
        }
    });
}

KODAWARI_C_API kodawari_status kodawari_bird_world_get_info(kodawari_bird_world* world, kodawari_bird_world_info* out) {
    return guard("kodawari_bird_world_get_info", world ? &world->message : nullptr, [&] {
        require_world(world);
        require_pointer(out, "out");
        kodawari_bird_world_info info{};
        info.route_count = static_cast<std::uint32_t>(world->world.routes.size());
        info.bird_count = static_cast<std::uint32_t>(world->world.birds.size());
        info.next_frame = world->next_frame;
        info.fps = world->world.fps;
        info.backend = backend_enum(world->kind);
        info.validation_messages = world->backend->validation_messages();
        copy_text(world->backend->device(), info.device, sizeof info.device);
        copy_text(world->fallback_reason, info.fallback_reason, sizeof info.fallback_reason);
        *out = info;
    });
}

}  // extern "C"
