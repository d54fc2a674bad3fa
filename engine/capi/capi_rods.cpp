// The C API's chain worlds (SPEC A): a rods::RodWorld built from the caller's arrays, a
// rod backend that simulates it, and frames converted to rods::RodFrame. Every argument is
// checked here, with the argument's path in the message, before anything changes; the
// engine's own checks (make_chain_template, finalize, check_frame) stay behind them as a
// second line, so that no assert of the solver is reachable from C.
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "capi/capi_common.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/rods/world.hpp"

using namespace kodawari;
using namespace kodawari::capi;

/// The opaque handle of kodawari.h.
struct kodawari_chain_world {
    std::string message;  // the last call's (kodawari_chain_world_last_error)
    rods::RodWorld world;  // the backend keeps a pointer to it: the handle never moves it
    /// Where each collider rides when a frame leaves the colliders out; empty when the
    /// caller gave no attachments (then every frame must give them).
    std::vector<kodawari_collider_desc> attachments;
    std::unique_ptr<RodBackend> backend;
    BackendKind kind = BackendKind::CpuReference;
    std::string fallback_reason;
    rods::RodFrame frame;     // the last step's input, reused (no allocation per step)
    ChainSnapshot snapshot;   // read()'s scratch, reused
    double time = 0.0;        // s since create or reset (RodFrame::time)
    rods::WindField wind;     // kodawari_chain_world_set_wind's (calm by default)
};

namespace {

// Limits of the C API, the same figures as the scene files' (scene/character_loader.hpp).
constexpr double kMaxShape = 100.0;   // chain shape coordinates, m
constexpr double kMaxLocal = 1000.0;  // collider attachments, m
constexpr double kMaxWorld = 1e6;     // world positions, m
// The solver's limit on a segment (rods/shape.cpp): a shorter one has no direction.
constexpr float kMinSegment = 1e-6f;

// A shape in the root's frame: positions (joint 0 at the origin, segments long enough)
// and unit orientations, or the default orientations.
rods::ChainShape read_shape(const kodawari_chain_shape& shape, std::uint32_t joints, const std::string& what) {
    require_pointer(shape.positions, what + ".positions");
    rods::ChainShape out;
    out.positions.resize(joints);
    for (std::uint32_t i = 0; i < joints; ++i) {
        const std::string p = at(what + ".positions", i);
        require_point(shape.positions + 3 * i, kMaxShape, p);
        out.positions[i] = vec3(shape.positions + 3 * i);
        if (i == 0 && out.positions[0] != glm::vec3(0.0f)) {
            invalid(p, "(" + number(out.positions[0].x) + ", " + number(out.positions[0].y) + ", " +
                           number(out.positions[0].z) +
                           "); expected (0, 0, 0): joint 0 sits on the chain root (move the chain with its root transform)");
        }
        // The same float arithmetic as rods::make_basis, so that both draw the line alike.
        if (i > 0) {
            const float length = glm::length(out.positions[i] - out.positions[i - 1]);
            if (!(length >= kMinSegment)) {
                invalid(p, number(length) + " m from joint " + std::to_string(i - 1) + "; segments must be at least " +
                               number(kMinSegment) + " m long");
            }
        }
    }
    if (shape.orientations == nullptr) {
        rods::default_orientations(out);
        return out;
    }
    out.orientations.resize(joints);
    for (std::uint32_t i = 0; i < joints; ++i) {
        require_unit_quat(shape.orientations + 4 * i, at(what + ".orientations", i));
        out.orientations[i] = quat(shape.orientations + 4 * i);
    }
    return out;
}

rods::SolverParams read_solver(const kodawari_solver_params& s, const std::string& what) {
    // A floor on max_substep (the engine takes any > 0) bounds a frame's substeps at
    // 1 s / 1e-4 s = 10,000: a tiny value would otherwise hang the step.
    require_range(s.max_substep, 1e-4, 0.05, what + ".max_substep");
    if (s.iterations < 1 || s.iterations > 64) invalid(what + ".iterations", std::to_string(s.iterations) + "; expected 1 to 64");
    require_range(s.stiffness, 0.0, 1.0, what + ".stiffness");
    require_range(s.rest_stiffness, 0.0, 1.0, what + ".rest_stiffness");
    require_range(s.damping, 0.0, 1000.0, what + ".damping");
    require_point(s.gravity, 1000.0, what + ".gravity");
    require_point(s.wind, 1000.0, what + ".wind");
    require_range(s.momentum_suppression, 0.0, 1.0, what + ".momentum_suppression");
    if (s.settle_start > 1) invalid(what + ".settle_start", std::to_string(s.settle_start) + "; expected 0 or 1");
    require_range(s.teleport_distance, 0.0, 1e6, what + ".teleport_distance", true);
    require_range(s.normal_drag, 0.0, 1000.0, what + ".normal_drag");
    require_range(s.tangent_drag, 0.0, 1000.0, what + ".tangent_drag");
    rods::SolverParams p;
    p.max_substep = s.max_substep;
    p.iterations = s.iterations;
    p.stiffness = s.stiffness;
    p.rest_stiffness = s.rest_stiffness;
    p.damping = s.damping;
    p.gravity = vec3(s.gravity);
    p.wind = vec3(s.wind);
    p.momentum_suppression = s.momentum_suppression;
    p.settle_start = s.settle_start != 0;
    p.teleport_distance = s.teleport_distance;
    p.normal_drag = s.normal_drag;
    p.tangent_drag = s.tangent_drag;
    return p;
}

rods::ChainTemplate read_template(const kodawari_chain_template_desc& t, const std::string& what) {
    if (t.joint_count < 2 || t.joint_count > rods::kMaxChainJoints) {
        invalid(what + ".joint_count",
                std::to_string(t.joint_count) + "; expected 2 to " + std::to_string(rods::kMaxChainJoints));
    }
    const rods::ChainShape base = read_shape(t.base, t.joint_count, what + ".base");
    if (t.view_count > rods::kMaxViewExamples) {
        invalid(what + ".view_count",
                std::to_string(t.view_count) + "; expected 0 to " + std::to_string(rods::kMaxViewExamples));
    }
    require_array(t.views, t.view_count, what + ".views", what + ".view_count");
    std::vector<rods::ChainShape> shapes;
    std::vector<rods::ViewExample> views;
    for (std::uint32_t k = 0; k < t.view_count; ++k) {
        const kodawari_view_example& v = t.views[k];
        const std::string view = at(what + ".views", k);
        require_direction(v.direction, view + ".direction");
        require_range(v.influence, 0.0, rods::kMaxInfluence, view + ".influence", true);
        shapes.push_back(read_shape(v.shape, t.joint_count, view + ".shape"));
        views.push_back(rods::ViewExample{vec3(v.direction), v.influence});
    }
    require_range(t.thickness, rods::kMinThickness, rods::kMaxThickness, what + ".thickness");
    require_range(t.mass, rods::kMinMass, rods::kMaxMass, what + ".mass");
    const rods::SolverParams params = read_solver(t.solver, what + ".solver");
    auto made = rods::make_chain_template(what, base, shapes, views, t.thickness, t.mass, params);
    check(made);
    if (t.limit_count != 0 && t.limit_count + 1 != t.joint_count) {
        invalid(what + ".limit_count", std::to_string(t.limit_count) + "; expected 0 or joint_count - 1 (" +
                                           std::to_string(t.joint_count - 1) + ")");
    }
    require_array(t.limits, t.limit_count, what + ".limits", what + ".limit_count");
    std::vector<rods::AngleLimit> limits;
    for (std::uint32_t i = 0; i < t.limit_count; ++i) {
        const kodawari_angle_limit& l = t.limits[i];
        const std::string limit = at(what + ".limits", i);
        if (l.kind > KODAWARI_LIMIT_SPHERICAL) invalid(limit + ".kind", std::to_string(l.kind) + "; expected a kodawari_limit_kind");
        limits.push_back({static_cast<rods::LimitKind>(l.kind), l.angle, l.yaw,
                          glm::quat(l.rotation[3], l.rotation[0], l.rotation[1], l.rotation[2])});
    }
    check(rods::set_limits(made.value().chain, limits, what + ".limits"));
    return std::move(made).value();
}

// The world of `desc` (templates, chains, counts, finalized) and its collider attachments.
void read_world(const kodawari_chain_world_desc& desc, rods::RodWorld& world,
                std::vector<kodawari_collider_desc>& attachments) {
    if (desc.template_count == 0) invalid("desc->template_count", "0; expected at least one chain template");
    require_array(desc.templates, desc.template_count, "desc->templates", "desc->template_count");
    if (desc.chain_count == 0) invalid("desc->chain_count", "0; expected at least one chain");
    require_array(desc.chains, desc.chain_count, "desc->chains", "desc->chain_count");
    if (desc.character_count == 0) invalid("desc->character_count", "0; expected at least one character");
    require_array(desc.colliders, desc.colliders != nullptr ? desc.collider_count : 0, "desc->colliders",
                  "desc->collider_count");
    for (std::uint32_t i = 0; i < desc.template_count; ++i) {
        world.templates.push_back(read_template(desc.templates[i], at("desc->templates", i)));
    }
    for (std::uint32_t c = 0; c < desc.chain_count; ++c) {
        const kodawari_chain_desc& d = desc.chains[c];
        const std::string what = at("desc->chains", c);
        if (d.template_index >= desc.template_count) {
            invalid(what + ".template_index", std::to_string(d.template_index) + "; expected an index below desc->template_count (" +
                                                  std::to_string(desc.template_count) + ")");
        }
        if (d.character >= desc.character_count) {
            invalid(what + ".character", std::to_string(d.character) + "; expected an index below desc->character_count (" +
                                             std::to_string(desc.character_count) + ")");
        }
        if (d.collider_count > rods::kMaxChainColliders) {
            invalid(what + ".collider_count", std::to_string(d.collider_count) + "; expected at most " +
                                                  std::to_string(rods::kMaxChainColliders) + " colliders per chain");
        }
        if (d.collider_begin > desc.collider_count || d.collider_count > desc.collider_count - d.collider_begin) {
            invalid(what + ".collider_begin", "colliders [" + std::to_string(d.collider_begin) + ", " +
                                                  std::to_string(std::uint64_t{d.collider_begin} + d.collider_count) +
                                                  ") do not fit in desc->collider_count (" +
                                                  std::to_string(desc.collider_count) + ")");
        }
        world.chains.push_back(rods::ChainInstance{d.template_index, d.character, d.collider_begin, d.collider_count, 0});
    }
    if (desc.colliders != nullptr) {
        for (std::uint32_t i = 0; i < desc.collider_count; ++i) {
            const kodawari_collider_desc& a = desc.colliders[i];
            const std::string what = at("desc->colliders", i);
            if (a.character >= desc.character_count) {
                invalid(what + ".character", std::to_string(a.character) + "; expected an index below desc->character_count (" +
                                                 std::to_string(desc.character_count) + ")");
            }
            require_capsule(a.local, kMaxLocal, what + ".local");
        }
        attachments.assign(desc.colliders, desc.colliders + desc.collider_count);
    }
    world.character_count = desc.character_count;
    world.collider_count = desc.collider_count;
    world.wind_count = 1;  // kodawari_chain_world_set_wind's field, every chain's
    check(world.finalize());
}

// Checks `frame` against `w` without changing anything (`what` names the argument).
void check_frame_args(const kodawari_chain_world& w, const kodawari_chain_frame* frame, const std::string& what,
                      bool uses_dt) {
    require_pointer(frame, what);
    const kodawari_chain_frame& f = *frame;
    // At most 1 s: with max_substep >= 1e-4 s a frame runs at most 10,000 substeps.
    if (uses_dt) require_range(f.dt, rods::kMinFrameDt, 1.0, what + "->dt");
    require_camera(f.camera, what + "->camera");
    const auto count = [&](std::uint32_t given, std::uint32_t expected, const std::string& name, const std::string& per) {
        if (given != expected) {
            invalid(what + "->" + name, std::to_string(given) + "; expected " + std::to_string(expected) + " (" + per + ")");
        }
    };
    count(f.reference_count, w.world.character_count, "reference_count", "one per character");
    require_array(f.references, f.reference_count, what + "->references", what + "->reference_count");
    for (std::uint32_t i = 0; i < f.reference_count; ++i) require_transform(f.references[i], at(what + "->references", i));
    count(f.root_count, static_cast<std::uint32_t>(w.world.chains.size()), "root_count", "one per chain");
    require_array(f.roots, f.root_count, what + "->roots", what + "->root_count");
    for (std::uint32_t i = 0; i < f.root_count; ++i) require_transform(f.roots[i], at(what + "->roots", i));
    if (f.colliders == nullptr) {
        if (f.collider_count != 0) {
            invalid(what + "->colliders", "is NULL, but " + what + "->collider_count is " + std::to_string(f.collider_count));
        }
        if (w.world.collider_count > 0 && w.attachments.empty()) {
            invalid(what + "->colliders", "is NULL, but the world's " + std::to_string(w.world.collider_count) +
                                              " colliders have no attachments (desc->colliders was NULL); give them in world space");
        }
        return;
    }
    count(f.collider_count, w.world.collider_count, "collider_count", "the world's colliders");
    for (std::uint32_t i = 0; i < f.collider_count; ++i) require_capsule(f.colliders[i], kMaxWorld, at(what + "->colliders", i));
}

rods::Transform transform(const kodawari_transform& t) { return {vec3(t.position), quat(t.rotation)}; }

// The engine's frame of a checked `f`, into `out` (its storage reused).
void fill_frame(const kodawari_chain_world& w, const kodawari_chain_frame& f, float dt, double time, rods::RodFrame& out) {
    out.time = static_cast<float>(time);
    out.dt = dt;
    out.camera.projection = f.camera.orthographic ? rods::Camera::Projection::Orthographic : rods::Camera::Projection::Perspective;
    out.camera.position = vec3(f.camera.position);
    out.camera.forward = glm::normalize(vec3(f.camera.forward));
    out.reference.resize(f.reference_count);
    for (std::uint32_t i = 0; i < f.reference_count; ++i) out.reference[i] = transform(f.references[i]);
    out.roots.resize(f.root_count);
    for (std::uint32_t i = 0; i < f.root_count; ++i) out.roots[i] = transform(f.roots[i]);
    out.colliders.resize(w.world.collider_count);
    for (std::uint32_t i = 0; i < w.world.collider_count; ++i) {
        if (f.colliders != nullptr) {
            const kodawari_capsule& c = f.colliders[i];
            out.colliders[i] = rods::Collider{vec3(c.a), vec3(c.b), c.radius};
            continue;
        }
        // Rides on its character's reference joint (kodawari_collider_desc).
        const kodawari_collider_desc& a = w.attachments[i];
        const rods::Transform& ref = out.reference[a.character];
        out.colliders[i] = rods::Collider{ref.position + ref.rotation * vec3(a.local.a),
                                         ref.position + ref.rotation * vec3(a.local.b), a.local.radius};
    }
    out.winds.assign(1, w.wind);
    // The engine's own check, behind ours.
    check(rods::check_frame(w.world, out));
}

void open_and_load(kodawari_chain_world& w, const kodawari_backend_options& options) {
    w.backend = capi::open_and_load<RodBackend>(options, w.kind, w.fallback_reason, make_rod_backend,
                                               [&](RodBackend& backend) { return backend.load(w.world, w.frame); });
}

void require_world(const kodawari_chain_world* world) { require_pointer(world, "world"); }

}  // namespace

extern "C" {

KODAWARI_C_API kodawari_status kodawari_solver_params_default(kodawari_solver_params* out) {
    return guard("kodawari_solver_params_default", nullptr, [&] {
        require_pointer(out, "out");
        const rods::SolverParams p;
        kodawari_solver_params s{};
        s.max_substep = p.max_substep;
        s.iterations = p.iterations;
        s.stiffness = p.stiffness;
        s.rest_stiffness = p.rest_stiffness;
        s.damping = p.damping;
        for (int i = 0; i < 3; ++i) {
            s.gravity[i] = p.gravity[i];
            s.wind[i] = p.wind[i];
        }
        s.momentum_suppression = p.momentum_suppression;
        s.settle_start = p.settle_start ? 1u : 0u;
        s.teleport_distance = p.teleport_distance;
        s.normal_drag = p.normal_drag;
        s.tangent_drag = p.tangent_drag;
        *out = s;
    });
}

KODAWARI_C_API kodawari_status kodawari_wind_default(kodawari_wind* out) {
    return guard("kodawari_wind_default", nullptr, [&] {
        require_pointer(out, "out");
        *out = to_c(rods::WindField{});
    });
}

KODAWARI_C_API kodawari_status kodawari_chain_world_set_wind(kodawari_chain_world* world, const kodawari_wind* wind) {
    return guard("kodawari_chain_world_set_wind", world ? &world->message : nullptr, [&] {
        require_world(world);
        world->wind = wind != nullptr ? read_wind(*wind, "wind") : rods::WindField{};
    });
}

KODAWARI_C_API kodawari_status kodawari_chain_world_create(const kodawari_chain_world_desc* desc,
                                                           const kodawari_chain_frame* initial,
                                                           kodawari_chain_world** out) {
    return guard("kodawari_chain_world_create", nullptr, [&] {
        require_pointer(out, "out");
        *out = nullptr;
        require_pointer(desc, "desc");
        require_backend_options(desc->backend, "desc->backend");
        auto w = std::make_unique<kodawari_chain_world>();
        read_world(*desc, w->world, w->attachments);
        check_frame_args(*w, initial, "initial", false);
        fill_frame(*w, *initial, 1.0f / 60.0f, 0.0, w->frame);
        open_and_load(*w, desc->backend);
        *out = w.release();
    });
}

KODAWARI_C_API void kodawari_chain_world_destroy(kodawari_chain_world* world) {
    // The destructors free memory and Vulkan objects; none of them throws.
    delete world;
}

KODAWARI_C_API const char* kodawari_chain_world_last_error(const kodawari_chain_world* world) {
    return world != nullptr ? world->message.c_str() : "";
}

KODAWARI_C_API kodawari_status kodawari_chain_world_reset(kodawari_chain_world* world, const kodawari_chain_frame* frame) {
    return guard("kodawari_chain_world_reset", world ? &world->message : nullptr, [&] {
        require_world(world);
        check_frame_args(*world, frame, "frame", false);
        fill_frame(*world, *frame, 1.0f / 60.0f, 0.0, world->frame);
        world->time = 0.0;
        check(world->backend->load(world->world, world->frame));
    });
}

KODAWARI_C_API kodawari_status kodawari_chain_world_step(kodawari_chain_world* world, const kodawari_chain_frame* frame) {
    return guard("kodawari_chain_world_step", world ? &world->message : nullptr, [&] {
        require_world(world);
        check_frame_args(*world, frame, "frame", true);
        const double time = world->time + static_cast<double>(frame->dt);
        fill_frame(*world, *frame, frame->dt, time, world->frame);
        check(world->backend->step(world->frame));
        world->time = time;
    });
}

KODAWARI_C_API kodawari_status kodawari_chain_world_record_step(kodawari_chain_world* world, void* command_buffer,
                                                                const kodawari_chain_frame* frame) {
    return guard("kodawari_chain_world_record_step", world ? &world->message : nullptr, [&] {
        require_world(world);
        require_pointer(command_buffer, "command_buffer");
        if (world->backend->device_data() == nullptr) {
            invalid("world", "runs on the " + std::string(world->backend->name()) +
                                 " backend; recording needs a vulkan world (backend options with vulkan_device)");
        }
        check_frame_args(*world, frame, "frame", true);
        const double time = world->time + static_cast<double>(frame->dt);
        fill_frame(*world, *frame, frame->dt, time, world->frame);
        check(record_step(*world->backend, static_cast<VkCommandBuffer>(command_buffer), world->frame));
        world->time = time;
    });
}

KODAWARI_C_API kodawari_status kodawari_chain_world_buffer(kodawari_chain_world* world, kodawari_device_buffer which,
                                                           kodawari_buffer_range* out) {
    return guard("kodawari_chain_world_buffer", world ? &world->message : nullptr, [&] {
        require_world(world);
        fill_range(world->backend->device_data(), which, out, true);
    });
}

KODAWARI_C_API kodawari_status kodawari_chain_world_read(kodawari_chain_world* world, const kodawari_chain_output* out) {
    return guard("kodawari_chain_world_read", world ? &world->message : nullptr, [&] {
        require_world(world);
        require_pointer(out, "out");
        const std::size_t joints = world->world.joint_count;
        const std::size_t chains = world->world.chains.size();
        require_chain_output(*out, joints, chains);
        ChainSnapshot& s = world->snapshot;
        check(world->backend->read(s));
        write_chain_output(s, *out);
    });
}

KODAWARI_C_API kodawari_status kodawari_chain_world_chain_joints(kodawari_chain_world* world, uint32_t chain,
                                                                 uint32_t* joint_begin, uint32_t* joint_count) {
    return guard("kodawari_chain_world_chain_joints", world ? &world->message : nullptr, [&] {
        require_world(world);
        const std::size_t chains = world->world.chains.size();
        if (chain >= chains) {
            invalid("chain", std::to_string(chain) + "; expected an index below the world's chain count (" +
                                 std::to_string(chains) + ")");
        }
        const rods::ChainInstance& c = world->world.chains[chain];
        if (joint_begin != nullptr) *joint_begin = c.joint_begin;
        if (joint_count != nullptr) *joint_count = world->world.templ(c).chain.joint_count;
    });
}

KODAWARI_C_API kodawari_status kodawari_chain_world_get_info(kodawari_chain_world* world, kodawari_chain_world_info* out) {
    return guard("kodawari_chain_world_get_info", world ? &world->message : nullptr, [&] {
        require_world(world);
        require_pointer(out, "out");
        kodawari_chain_world_info info{};
        info.template_count = static_cast<std::uint32_t>(world->world.templates.size());
        info.chain_count = static_cast<std::uint32_t>(world->world.chains.size());
        info.joint_count = world->world.joint_count;
        info.character_count = world->world.character_count;
        info.collider_count = world->world.collider_count;
        info.backend = backend_enum(world->kind);
        info.validation_messages = world->backend->validation_messages();
        copy_text(world->backend->device(), info.device, sizeof info.device);
        copy_text(world->fallback_reason, info.fallback_reason, sizeof info.fallback_reason);
        *out = info;
    });
}

}  // extern "C"
