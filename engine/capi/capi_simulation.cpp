// The C API's scene simulations (issue 33): a scene file opened as kodawari::Simulation,
// stepped, read and baked through kodawari::bake with the glTF sinks, as `kodawari run`
// does. Every use of the C++ Simulation and bake API is in this file, so that a change
// of that API (issue 31) is adapted here alone. Arguments are checked before anything
// changes, as everywhere in the C API (capi_common.hpp).
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <vulkan/vulkan_core.h>

#include "capi/capi_bird_pose.hpp"
#include "capi/capi_common.hpp"
#include "kodawari/simulation/bake.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/domains/flocking.hpp"
#include "kodawari/export/export.hpp"
#include "kodawari/rods/lod.hpp"
#include "kodawari/simulation/simulation.hpp"

using namespace kodawari;
using namespace kodawari::capi;

/// The opaque handle of kodawari.h.
struct kodawari_simulation {
    std::string message;  // the last call's (kodawari_simulation_last_error)
    std::unique_ptr<Simulation> sim;
    SimulationOptions options;  // what bake() opens its own simulation with
    std::uint32_t next_frame = 0;
    bool recorded = false;             // the last frame was recorded (its poses are on the device)
    std::vector<gpu::BirdPose> poses;  // the last frame's, read back by step()
    ChainSnapshot chains;              // read_chains()' scratch, reused
    std::vector<rods::Level> levels;   // chain_levels()' scratch, reused
    std::vector<std::uint8_t> kept;    // and which chains kept their state
    std::array<PartOffsets, birds::kWingTypeCount> offsets{};
};

namespace {

void require_sim(const kodawari_simulation* sim) { require_pointer(sim, "sim"); }

void require_stepped(const kodawari_simulation& sim) {
    if (sim.next_frame == 0) invalid("sim", "no frame simulated yet; call kodawari_simulation_step first");
}

// The host's copy of the last frame's poses: not of a recorded frame.
void require_poses(const kodawari_simulation& sim) {
    require_stepped(sim);
    if (sim.recorded) {
        invalid("sim", "the last frame was recorded into a command buffer: its poses are on the device "
                       "(kodawari_simulation_buffer); kodawari_simulation_step reads them back");
    }
}

// A file that cannot be read is the caller's argument, as a file that is not a scene: the
// engine reports both (Io, InvalidInput) with the path in the message.
[[noreturn]] void fail_on_file(const Error& error) {
    if (error.kind == Error::Kind::Io) reject(KODAWARI_INVALID_ARGUMENT, error.message);
    fail(error);
}

// `kodawari run`'s files (glb_bake_paths): one per kind of content.
std::vector<std::unique_ptr<BakeSink>> glb_sinks(const std::string& path, bool has_birds, bool has_chains,
                                                 const GlbCompaction& compaction) {
    const std::vector<std::string> paths = glb_bake_paths(path, has_birds, has_chains);
    std::vector<std::unique_ptr<BakeSink>> sinks;
    if (has_birds) sinks.push_back(make_birds_glb_sink(paths.front(), compaction));
    if (has_chains) sinks.push_back(make_chains_glb_sink(paths.back(), compaction));
    return sinks;
}

FlockAgent flock_agent(const kodawari_flock_agent& a) {
    FlockAgent f;
    // Out-of-range kinds reach set_flock_agents as themselves, which names them.
    f.kind = static_cast<FlockAgent::Kind>(a.kind);
    f.position = {a.position[0], a.position[1], a.position[2]};
    f.velocity = {a.velocity[0], a.velocity[1], a.velocity[2]};
    f.radius = a.radius;
    f.weight = a.weight;
    f.margin = a.margin;
    f.end = {a.end[0], a.end[1], a.end[2]};
    f.normal = {a.normal[0], a.normal[1], a.normal[2]};
    return f;
}

}  // namespace

extern "C" {

KODAWARI_C_API kodawari_status kodawari_simulation_open(const char* path, const kodawari_backend_options* backend,
                                                        uint32_t frames, kodawari_simulation** out) {
    return guard("kodawari_simulation_open", nullptr, [&] {
        require_pointer(out, "out");
        *out = nullptr;
        require_pointer(path, "path");
        if (path[0] == '\0') invalid("path", "\"\"; expected a scene file (SCENE.json)");
        const kodawari_backend_options zero{};
        const kodawari_backend_options& b = backend != nullptr ? *backend : zero;
        require_backend_options(b, "backend");
        auto s = std::make_unique<kodawari_simulation>();
        const kodawari_backend kind = effective_backend(b);
        if (kind != KODAWARI_BACKEND_AUTO) s->options.backend = backend_kind(kind);
        s->options.options = backend_options(b);
        if (frames > kMaxSimulationFrames) {
            invalid("frames", std::to_string(frames) + "; expected 0 (the scene's) or 1 to " + std::to_string(kMaxSimulationFrames));
        }
        if (frames != 0) s->options.frames = frames;
        auto opened = Simulation::open(path, s->options);
        if (!opened.ok()) fail_on_file(opened.error());
        s->sim = std::move(opened).value();
        s->offsets = all_part_offsets();
        *out = s.release();
    });
}

KODAWARI_C_API void kodawari_simulation_destroy(kodawari_simulation* sim) { delete sim; }

KODAWARI_C_API const char* kodawari_simulation_last_error(const kodawari_simulation* sim) {
    return sim != nullptr ? sim->message.c_str() : "";
}

KODAWARI_C_API kodawari_status kodawari_simulation_set_wind(kodawari_simulation* sim, const kodawari_wind* wind) {
    return guard("kodawari_simulation_set_wind", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        std::optional<rods::WindField> field;
        if (wind != nullptr) field = read_wind(*wind, "wind");
        check(set_wind(*sim->sim, field));
    });
}

KODAWARI_C_API kodawari_status kodawari_simulation_set_lod_budget(kodawari_simulation* sim, float budget_ms, int measured) {
    return guard("kodawari_simulation_set_lod_budget", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        check(set_lod_budget(*sim->sim, budget_ms, measured != 0));
    });
}

KODAWARI_C_API kodawari_status kodawari_simulation_lod_budget(kodawari_simulation* sim, kodawari_lod_budget* out) {
    return guard("kodawari_simulation_lod_budget", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        require_pointer(out, "out");
        *out = kodawari_lod_budget{};
        const auto budget = lod_budget(*sim->sim);
        if (!budget) return;
        out->active = 1;
        out->measured = budget->measured ? 1 : 0;
        out->budget_ms = budget->budget_ms;
        out->scale = budget->scale;
        out->full_distance = budget->full_distance;
        out->modelled_ms = static_cast<float>(budget->modelled_ms);
    });
}

KODAWARI_C_API kodawari_status kodawari_flock_agent_default(kodawari_flock_agent* out) {
    return guard("kodawari_flock_agent_default", nullptr, [&] {
        require_pointer(out, "out");
        const FlockAgent d;
        *out = kodawari_flock_agent{static_cast<std::uint32_t>(d.kind),
                                    {0.0f, 0.0f, 0.0f},
                                    {0.0f, 0.0f, 0.0f},
                                    d.radius,
                                    d.weight,
                                    d.margin,
                                    {d.end.x, d.end.y, d.end.z},
                                    {d.normal.x, d.normal.y, d.normal.z}};
    });
}

KODAWARI_C_API kodawari_status kodawari_simulation_set_flock_agents(kodawari_simulation* sim, const kodawari_flock_agent* agents,
                                                                    uint32_t count) {
    return guard("kodawari_simulation_set_flock_agents", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        require_array(agents, count, "agents", "count");
        std::vector<FlockAgent> list;
        for (std::uint32_t i = 0; i < count; ++i) list.push_back(flock_agent(agents[i]));
        check(set_flock_agents(*sim->sim, list));
    });
}

KODAWARI_C_API kodawari_status kodawari_simulation_set_flock_device_agents(kodawari_simulation* sim, uint32_t count) {
    return guard("kodawari_simulation_set_flock_device_agents", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        check(set_flock_device_agents(*sim->sim, count));
    });
}

KODAWARI_C_API kodawari_status kodawari_encode_flock_agent(const kodawari_flock_agent* agent, float out[12]) {
    return guard("kodawari_encode_flock_agent", nullptr, [&] {
        require_pointer(agent, "agent");
        require_pointer(out, "out");
        auto encoded = encode_flock_agent(flock_agent(*agent));
        check(encoded);
        static_assert(sizeof(gpu::FlockAgentGpu) == 12 * sizeof(float));
        std::memcpy(out, &encoded.value(), sizeof(gpu::FlockAgentGpu));
    });
}

KODAWARI_C_API kodawari_status kodawari_simulation_step(kodawari_simulation* sim, uint32_t frames) {
    return guard("kodawari_simulation_step", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        const std::uint32_t total = sim->sim->frame_count();
        const std::uint32_t left = total - sim->next_frame;
        if (left == 0) {
            invalid("frames", std::to_string(frames) + "; the simulation has stepped all its " + std::to_string(total) +
                                  " frames: expected no further step (open it with more frames to go on)");
        }
        if (frames < 1 || frames > left) {
            invalid("frames", std::to_string(frames) + "; expected 1 to " + std::to_string(left) + " (frame " +
                                  std::to_string(sim->next_frame) + " of " + std::to_string(total) + " is next)");
        }
        // Only the last frame's poses are kept: the frames before it are stepped without
        // reading anything back, so that a long step costs no memory per frame.
        if (frames > 1) check(sim->sim->step(frames - 1));
        const std::size_t birds = bird_world(*sim->sim).birds.size();
        sim->poses.resize(birds);
        check(step_birds(*sim->sim, 1, std::span<gpu::BirdPose>(sim->poses)));
        sim->next_frame += frames;
        sim->recorded = false;
    });
}

KODAWARI_C_API kodawari_status kodawari_simulation_record(kodawari_simulation* sim, void* command_buffer) {
    return guard("kodawari_simulation_record", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        require_pointer(command_buffer, "command_buffer");
        if (sim->options.backend != BackendKind::Vulkan || !sim->options.options.context) {
            invalid("sim", "opened without backend options' vulkan_device; recording needs the application's device");
        }
        const std::uint32_t total = sim->sim->frame_count();
        if (sim->next_frame >= total) {
            invalid("sim", "every frame is simulated (" + std::to_string(total) + "); no frame left to record");
        }
        check(sim->sim->record(static_cast<VkCommandBuffer>(command_buffer)));
        sim->next_frame += 1;
        sim->recorded = true;
    });
}

KODAWARI_C_API kodawari_status kodawari_simulation_buffer(kodawari_simulation* sim, kodawari_device_buffer which,
                                                          kodawari_buffer_range* out) {
    return guard("kodawari_simulation_buffer", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        require_pointer(out, "out");
        auto range = sim->sim->buffer(device_buffer(which));
        check(range);
        *out = buffer_range(range.value());
    });
}

KODAWARI_C_API kodawari_status kodawari_simulation_get_info(kodawari_simulation* sim, kodawari_simulation_info* out) {
    return guard("kodawari_simulation_get_info", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        require_pointer(out, "out");
        const Simulation& s = *sim->sim;
        kodawari_simulation_info info{};
        info.bird_count = static_cast<std::uint32_t>(bird_world(s).birds.size());
        if (const RodScene* rods = rod_scene(s)) {
            info.character_count = rods->world.character_count;
            info.chain_count = static_cast<std::uint32_t>(rods->world.chains.size());
            info.joint_count = rods->world.joint_count;
        }
        info.frame_count = s.frame_count();
        info.next_frame = sim->next_frame;
        info.fps = s.scene().fps;
        info.backend = backend_enum(s.backend());
        info.validation_messages = s.validation_messages();
        copy_text(s.scene().name, info.name, sizeof info.name);
        copy_text(s.device(), info.device, sizeof info.device);
        copy_text(s.fallback_reason(), info.fallback_reason, sizeof info.fallback_reason);
        *out = info;
    });
}

KODAWARI_C_API kodawari_status kodawari_simulation_bird_poses(kodawari_simulation* sim, const kodawari_bird_output* out) {
    return guard("kodawari_simulation_bird_poses", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        require_pointer(out, "out");
        require_poses(*sim);
        const std::size_t birds = sim->poses.size();
        const std::size_t needed = birds * kFloatsPerBird;
        const std::string why = std::to_string(birds) + " birds x " + std::to_string(KODAWARI_BIRD_PARTS) + " parts x " +
                                std::to_string(KODAWARI_TRANSFORM_FLOATS);
        require_capacity(out->local_transforms, out->local_transforms_capacity, needed, "out->local_transforms", why);
        require_capacity(out->world_transforms, out->world_transforms_capacity, needed, "out->world_transforms", why);
        const auto& params = bird_world(*sim->sim).birds;
        for (std::size_t i = 0; i < birds; ++i) {
            part_transforms(sim->poses[i], sim->offsets[params[i].ids.y],
                            out->local_transforms ? out->local_transforms + i * kFloatsPerBird : nullptr,
                            out->world_transforms ? out->world_transforms + i * kFloatsPerBird : nullptr);
        }
    });
}

KODAWARI_C_API kodawari_status kodawari_simulation_bird_tail_spreads(kodawari_simulation* sim, float* out,
                                                                     size_t capacity) {
    return guard("kodawari_simulation_bird_tail_spreads", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        require_poses(*sim);
        const std::size_t birds = sim->poses.size();
        require_array(out, birds, "out", "the bird count");
        if (capacity < birds) {
            reject(KODAWARI_BUFFER_TOO_SMALL, "out: holds " + std::to_string(capacity) + " floats, needs " +
                                                  std::to_string(birds) + " (one per bird)");
        }
        for (std::size_t i = 0; i < birds; ++i) out[i] = sim->poses[i].position.w;
    });
}

KODAWARI_C_API kodawari_status kodawari_simulation_read_chains(kodawari_simulation* sim, const kodawari_chain_output* out) {
    return guard("kodawari_simulation_read_chains", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        require_pointer(out, "out");
        require_stepped(*sim);
        const RodScene* rods = rod_scene(*sim->sim);
        if (rods == nullptr) return;  // no characters: 0 joints, nothing to write
        const std::size_t joints = rods->world.joint_count;
        const std::size_t chains = rods->world.chains.size();
        require_chain_output(*out, joints, chains);
        ChainSnapshot& s = sim->chains;
        check(read_chains(*sim->sim, s));
        write_chain_output(s, *out);
    });
}

static_assert(KODAWARI_LEVEL_FULL == static_cast<int>(rods::Level::Full) &&
              KODAWARI_LEVEL_POSED == static_cast<int>(rods::Level::Posed) &&
              KODAWARI_LEVEL_HIDDEN == static_cast<int>(rods::Level::Hidden) &&
              KODAWARI_LEVEL_REDUCED == static_cast<int>(rods::Level::Reduced));

KODAWARI_C_API kodawari_status kodawari_simulation_chain_levels(kodawari_simulation* sim, uint8_t* levels, uint8_t* kept,
                                                                size_t capacity) {
    return guard("kodawari_simulation_chain_levels", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        require_stepped(*sim);
        const RodScene* rods = rod_scene(*sim->sim);
        if (rods == nullptr) return;  // no characters: no chains, nothing to write
        const std::size_t chains = rods->world.chains.size();
        require_array(levels, chains, "levels", "the chain count");
        if (capacity < chains) {
            reject(KODAWARI_BUFFER_TOO_SMALL, "levels: holds " + std::to_string(capacity) + " bytes, needs " +
                                                  std::to_string(chains) + " (one per chain)");
        }
        check(read_chain_levels(*sim->sim, sim->levels, kept ? &sim->kept : nullptr));
        for (std::size_t c = 0; c < sim->levels.size(); ++c) levels[c] = static_cast<std::uint8_t>(sim->levels[c]);
        if (kept != nullptr) std::copy(sim->kept.begin(), sim->kept.end(), kept);
    });
}

KODAWARI_C_API kodawari_status kodawari_simulation_chain_joints(kodawari_simulation* sim, uint32_t chain,
                                                                uint32_t* joint_begin, uint32_t* joint_count) {
    return guard("kodawari_simulation_chain_joints", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        const RodScene* rods = rod_scene(*sim->sim);
        const std::size_t chains = rods != nullptr ? rods->world.chains.size() : 0;
        if (chain >= chains) {
            invalid("chain", std::to_string(chain) + "; expected an index below the scene's chain count (" +
                                 std::to_string(chains) + ")");
        }
        const rods::ChainInstance& c = rods->world.chains[chain];
        if (joint_begin != nullptr) *joint_begin = c.joint_begin;
        if (joint_count != nullptr) *joint_count = rods->world.templ(c).chain.joint_count;
    });
}

KODAWARI_C_API kodawari_status kodawari_simulation_bake(kodawari_simulation* sim, const char* path, uint32_t compact,
                                                        char* written, size_t written_size) {
    return guard("kodawari_simulation_bake", sim ? &sim->message : nullptr, [&] {
        require_sim(sim);
        require_pointer(path, "path");
        if (path[0] == '\0') invalid("path", "\"\"; expected an output file (OUT.glb)");
        if (const std::string problem = glb_name_problem(path); !problem.empty()) invalid("path", "\"" + std::string(path) + "\": " + problem);
        require_flag(compact, "compact");
        if (written != nullptr && written_size == 0) invalid("written_size", "0 with a written buffer; expected its size in bytes");
        // A simulation of its own from frame 0, so that `sim` keeps its frame.
        auto opened = Simulation::create(sim->sim->scene(), sim->options);
        check(opened);
        Simulation& baked = *opened.value();
        GlbCompaction compaction;
        compaction.enabled = compact != 0;
        const bool has_birds = !bird_world(baked).birds.empty(), has_chains = rod_scene(baked) != nullptr;
        // Never over the scene or a file it reads (a model named as its scene, in one folder).
        for (const std::string& out : glb_bake_paths(path, has_birds, has_chains)) {
            const std::string input = baked.scene().reads(out);
            if (input.empty()) continue;
            invalid("path", "\"" + out + "\" is " + (input == "the scene file" ? input + " itself" : input + " of the scene " + baked.scene().path) +
                                "; the bake would replace it: give another path");
        }
        auto sinks = glb_sinks(path, has_birds, has_chains, compaction);
        if (sinks.empty()) invalid("sim", "its scene has neither birds nor characters; nothing to bake");
        std::vector<BakeSink*> pointers;
        for (auto& sink : sinks) pointers.push_back(sink.get());
        auto files = bake(baked, pointers);
        if (!files.ok()) fail_on_file(files.error());
        if (written != nullptr) {
            std::string list;
            for (const BakeOutput& file : files.value()) list += (list.empty() ? "" : "\n") + file.path;
            copy_text(list, written, written_size);
        }
    });
}

}  // extern "C"
