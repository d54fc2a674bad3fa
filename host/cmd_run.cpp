// `kodawari run SCENE`: bakes a scene (Simulation, kodawari/simulation.hpp) into glTF
// and optionally a JSON Lines trace. I/O around the engine's frame protocol.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <vector>

#include "commands.hpp"
#include "kodawari/export.hpp"
#include "kodawari/rod_scene.hpp"
#include "kodawari/scene.hpp"
#include "kodawari/simulation.hpp"

namespace kodawari::cli {

namespace {

void print_wrote(const std::string& path, const char* what) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    std::printf("kodawari: wrote %s (%.1f MiB, glTF 2.0 binary%s)\n", path.c_str(), ec ? 0.0 : static_cast<double>(size) / (1 << 20),
                what);
}

// Baking more than this in memory is refused (the bake is held whole until written).
constexpr std::uint64_t kBakeLimitBytes = 6ull << 30;

// What a bake keeps of the characters' chains: per frame the snapshot into the trace, the
// rigged characters' own glTF and the procedural characters' bones.
struct ChainBake {
    Simulation& sim;
    const RodScene& rods_scene;
    std::string out_path;
    std::vector<std::uint32_t> characters, within;  // per chain: its character, its index there
    std::vector<RiggedCrowdExport> rigged;
    std::vector<std::string> rigged_paths;
    std::vector<glm::vec3> positions;
    std::vector<glm::quat> orientations;
    ChainSnapshot snapshot;

    [[nodiscard]] Result<void> begin() {
        const rods::RodWorld& world = rods_scene.world;
        const Scene& scene = sim.scene();
        std::printf("kodawari: scene \"%s\" (%s): %u characters, %zu chains, %zu joints, %u frames at %g fps\n",
                    scene.name.c_str(), scene.path.c_str(), world.character_count, world.chains.size(),
                    std::size_t{world.joint_count}, sim.frame_count(), static_cast<double>(rods_scene.fps));
        std::fflush(stdout);
        characters.resize(world.chains.size());
        within.resize(world.chains.size());
        for (std::uint32_t c = 0; c < world.character_count; ++c) {
            for (std::uint32_t k = 0; k < rods_scene.chain_count(c); ++k) {
                characters[rods_scene.instances[c].chain_begin + k] = c;
                within[rods_scene.instances[c].chain_begin + k] = k;
            }
        }
        // Rigged characters go back into their own glTF, one file per character template
        // (the scene's out path when it is the only character); procedural characters (and
        // then the rigged ones too, as bones) into write_chains_glb's file.
        const bool any_procedural = std::any_of(rods_scene.characters.begin(), rods_scene.characters.end(),
                                                [](const CharacterKinematics& k) { return !k.rig; });
        if (!out_path.empty()) {
            const std::string stem = out_path.substr(0, out_path.size() - (out_path.ends_with(".glb") ? 4 : 0));
            for (std::uint32_t k = 0; k < rods_scene.characters.size(); ++k) {
                if (!rods_scene.characters[k].rig) continue;
                auto e = RiggedCrowdExport::create(rods_scene, k);
                if (!e) return e.error();
                if (e.value().instances().empty()) continue;
                rigged.push_back(std::move(e).value());
                rigged_paths.push_back(!any_procedural && rods_scene.characters.size() == 1
                                           ? out_path
                                           : stem + "-" + rods_scene.characters[k].name + ".glb");
            }
        }
        positions.resize(out_path.empty() || !any_procedural ? 0 : std::size_t{sim.frame_count()} * world.joint_count);
        orientations.resize(positions.size());
        return {};
    }

    [[nodiscard]] Result<void> frame(std::uint32_t f, std::optional<TraceWriter>& trace) {
        if (trace || !positions.empty() || !rigged.empty()) KW_TRY(sim.read_chains(snapshot));
        for (RiggedCrowdExport& e : rigged) KW_TRY(e.add_frame(f, snapshot));
        if (trace) trace->write_chains(f, rods_scene.time(f), rods_scene.world, characters, within, rods_scene.chain_names, snapshot);
        if (!positions.empty()) {
            const auto at = static_cast<std::ptrdiff_t>(std::size_t{f} * rods_scene.world.joint_count);
            std::copy(snapshot.positions.begin(), snapshot.positions.end(), positions.begin() + at);
            std::copy(snapshot.orientations.begin(), snapshot.orientations.end(), orientations.begin() + at);
        }
        return {};
    }

    void print_timing() const {
        const SimulationTiming& timing = sim.timing();
        const std::uint32_t frames = sim.frame_count();
        const std::uint32_t steps = std::max(frames, 2u) - 1;
        std::printf("kodawari: backend %s on %s: %.3f ms per frame", std::string(backend_name(sim.backend())).c_str(),
                    sim.device().c_str(), 1e3 * timing.chain_seconds / frames);
        if (timing.chain_gpu_ms > 0.0) std::printf(" (GPU %.3f ms)", timing.chain_gpu_ms / steps);
        std::printf(", %.3g joint-steps/s%s\n",
                    static_cast<double>(rods_scene.world.joint_count) * steps / std::max(timing.chain_seconds, 1e-9),
                    sim.rod_inputs_on_device() ? "; rigged characters' rod input written on the device" : "");
    }

    [[nodiscard]] Result<void> finish() {
        for (std::size_t i = 0; i < rigged.size(); ++i) {
            KW_TRY(rigged[i].finish(rigged_paths[i]));
            print_wrote(rigged_paths[i], ", the character's own skeleton and meshes");
        }
        if (!positions.empty()) {
            KW_TRY(write_chains_glb(out_path, rods_scene, sim.frame_count(), positions, orientations));
            print_wrote(out_path, "");
        }
        return {};
    }
};

// What a bake keeps of the birds: every frame's poses for the glTF, and the trace.
struct BirdBake {
    Simulation& sim;
    std::string out_path;
    std::vector<gpu::BirdPose> poses;  // frames x birds, for the export
    std::vector<gpu::BirdPose> chunk_poses;
    std::vector<gpu::BirdDiag> chunk_diag;

    [[nodiscard]] std::size_t count() const { return sim.bird_world().birds.size(); }

    void begin() {
        const Scene& scene = sim.scene();
        std::printf("kodawari: scene \"%s\" (%s): %zu birds, %u frames at %g fps\n", scene.name.c_str(), scene.path.c_str(),
                    count(), sim.frame_count(), static_cast<double>(sim.bird_world().fps));
        std::fflush(stdout);
        poses.resize(out_path.empty() ? 0 : std::size_t{sim.frame_count()} * count());
    }

    // Where the next `n` frames from `done` go.
    StepOutput output(std::uint32_t done, std::uint32_t n, bool tracing) {
        StepOutput out;
        if (!poses.empty()) out.bird_poses = std::span(poses).subspan(std::size_t{done} * count(), std::size_t{n} * count());
        if (tracing) {
            if (poses.empty()) {
                chunk_poses.resize(std::size_t{n} * count());
                out.bird_poses = chunk_poses;
            }
            chunk_diag.resize(std::size_t{n} * count());
            out.bird_diag = chunk_diag;
        }
        return out;
    }

    void trace_frames(std::uint32_t done, std::uint32_t n, const StepOutput& out, TraceWriter& trace) const {
        for (std::uint32_t k = 0; k < n; ++k) {
            trace.write_frame(done + k, sim.bird_world(), out.bird_poses.subspan(std::size_t{k} * count(), count()),
                              out.bird_diag.subspan(std::size_t{k} * count(), count()));
        }
    }

    void print_timing() const {
        const SimulationTiming& timing = sim.timing();
        const std::uint32_t frames = sim.frame_count();
        std::printf("kodawari: backend %s on %s: %.3f ms per frame", std::string(backend_name(sim.backend())).c_str(),
                    sim.device().c_str(), 1e3 * timing.bird_seconds / frames);
        if (timing.bird_gpu_timed) std::printf(" (GPU %.3f ms)", timing.bird_gpu_ms / frames);
        std::printf(", %.3g bird-frames/s\n", static_cast<double>(count()) * frames / std::max(timing.bird_seconds, 1e-9));
    }

    [[nodiscard]] Result<void> finish() {
        if (poses.empty()) return {};
        KW_TRY(write_birds_glb(out_path, sim.bird_world(), poses, sim.frame_count()));
        print_wrote(out_path, "");
        return {};
    }
};

// Every frame of the simulation into the bakes; birds in chunks of frames (one step each)
// when there are no chains to read per frame.
Result<void> bake(Simulation& sim, std::optional<BirdBake>& birds, std::optional<ChainBake>& chains,
                  std::optional<TraceWriter>& trace) {
    const std::uint32_t frames = sim.frame_count();
    if (birds) birds->begin();
    if (chains) KW_TRY(chains->begin());
    const std::size_t count = sim.bird_world().birds.size();
    const std::size_t per_frame = count + (sim.rod_scene() ? sim.rod_scene()->world.joint_count : 0);
    // Chunks bound the memory of traces and let the progress bar move.
    const std::uint32_t chunk = chains ? 1u
                                       : static_cast<std::uint32_t>(
                                             std::clamp<std::size_t>((1u << 20) / std::max<std::size_t>(count, 1), 1, 120));
    const bool show_progress = stderr_is_terminal() && std::uint64_t{frames} * per_frame >= 2'000'000;
    for (std::uint32_t done = 0; done < frames;) {
        const std::uint32_t n = std::min(chunk, frames - done);
        const StepOutput out = birds ? birds->output(done, n, trace.has_value()) : StepOutput{};
        KW_TRY(sim.step(n, out));
        if (birds && trace) birds->trace_frames(done, n, out, *trace);
        if (chains) KW_TRY(chains->frame(done, trace));
        done += n;
        if (show_progress) progress("simulating", done, frames);
    }
    if (birds) birds->print_timing();
    if (chains) chains->print_timing();
    if (validation_failed(sim.validation_messages())) return make_error(Error::Kind::Vulkan, "");
    if (birds) KW_TRY(birds->finish());
    if (chains) KW_TRY(chains->finish());
    return {};
}

// A bake held whole in memory must fit (issue 15 streams it instead).
Result<void> check_bake_size(const Simulation& sim) {
    const std::uint64_t frames = sim.frame_count();
    const auto refuse = [&](std::uint64_t count, const char* what, std::uint64_t bytes, const char* of) -> Result<void> {
        if (bytes <= kBakeLimitBytes) return {};
        return make_error(Error::Kind::InvalidInput, "baking " + std::to_string(count) + " " + what + " x " + std::to_string(frames) +
                                                         " frames needs " + std::to_string(bytes >> 20) + " MiB" + of +
                                                         "; use --frames or --no-export");
    };
    const std::uint64_t birds = sim.bird_world().birds.size();
    KW_TRY(refuse(birds, "birds", frames * birds * sizeof(gpu::BirdPose), " of poses"));
    const std::uint64_t joints = sim.rod_scene() ? sim.rod_scene()->world.joint_count : 0;
    return refuse(joints, "joints", frames * joints * (sizeof(glm::vec3) + sizeof(glm::quat)), "");
}

}  // namespace

int cmd_run(Args args) {
    const BackendChoice choice = read_backend_choice(args);
    const auto frames_option = args.count("frames", 1, 10'000'000);
    const auto out_option = args.option("out");
    const bool no_export = args.flag("no-export");
    const auto trace_path = args.option("trace");
    if (no_export && out_option) throw UsageError{"--out and --no-export exclude each other"};
    auto opened = open_simulation(scene_argument(args.positionals(), "run"), choice, frames_option);
    if (!opened) return report(opened.error());
    Simulation& sim = *opened.value();
    const Scene& scene = sim.scene();
    const bool has_birds = !sim.bird_world().birds.empty();
    const bool has_chains = sim.rod_scene() != nullptr;
    if (!no_export) {
        if (auto r = check_bake_size(sim); !r) return report(r.error());
    }
    if (!no_export && !out_option) {
        std::error_code ec;
        std::filesystem::create_directories("out", ec);
    }
    // One file per kind of content; a scene with both writes <out> for the birds and
    // <out without .glb>-characters.glb for the characters.
    const std::string base_out = out_option ? *out_option : "out/" + scene.name + ".glb";
    std::string chains_out;
    if (!no_export && has_chains) {
        chains_out = has_birds ? base_out.substr(0, base_out.size() - (base_out.ends_with(".glb") ? 4 : 0)) + "-characters.glb"
                               : base_out;
    }

    std::optional<TraceWriter> trace;
    if (trace_path) {
        auto t = TraceWriter::open(*trace_path, {scene.name, sim.bird_world().fps, sim.frame_count(),
                                                 std::string(backend_name(sim.backend()))});
        if (!t) return report(t.error());
        trace.emplace(std::move(t).value());
    }
    std::optional<BirdBake> birds;
    std::optional<ChainBake> chains;
    if (has_birds) birds.emplace(BirdBake{sim, no_export ? std::string() : base_out, {}, {}, {}});
    if (has_chains) chains.emplace(ChainBake{sim, *sim.rod_scene(), chains_out, {}, {}, {}, {}, {}, {}, {}});
    if (auto r = bake(sim, birds, chains, trace); !r) {
        // Validation has said why already.
        return r.error().message.empty() ? kExitFailure : report(r.error());
    }
    if (trace) {
        if (auto r = trace->finish(); !r) return report(r.error());
        std::printf("kodawari: wrote trace %s\n", trace_path->c_str());
    }
    return kExitOk;
}

}  // namespace kodawari::cli
