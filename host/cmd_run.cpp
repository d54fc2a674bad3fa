// `kodawari run SCENE`: bakes a scene (kodawari/simulation/bake.hpp) into glTF and optionally a
// JSON Lines trace. Arguments and messages around the engine's bake pipeline.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <utility>
#include <vector>

#include "bake_outputs.hpp"
#include "commands.hpp"
#include "kodawari/simulation/bake.hpp"
#include "kodawari/simulation/distributed.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/simulation/shards.hpp"
#ifdef KODAWARI_WITH_MPI
#include "mpi_communicator.hpp"
#endif
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/domains/trace.hpp"
#include "kodawari/simulation/simulation.hpp"

namespace kodawari::cli {

namespace {

// The scene's counts (a shard's or a rank's simulation holds part of it: its chains and
// joints are said as its own, print_shard() says which instances).
void print_scene(const Simulation& sim) {
    const Scene& scene = sim.scene();
    const bool part = sim.shard().shard.count > 1;
    const auto whole = [&](std::string_view noun, std::size_t own) {
        return part ? std::size_t{sim.shard().part(noun).scene_count} : own;
    };
    if (!bird_world(sim).birds.empty()) {
        std::printf("kodawari: scene \"%s\" (%s): %s, %s at %g fps\n", scene.name.c_str(), scene.path.c_str(),
                    counted(whole("birds", bird_world(sim).birds.size()), "bird").c_str(), counted(sim.frame_count(), "frame").c_str(),
                    static_cast<double>(bird_world(sim).fps));
    }
    if (const RodScene* rods = rod_scene(sim)) {
        const rods::RodWorld& world = rods->world;
        std::printf("kodawari: scene \"%s\" (%s): %s, %s, %s%s, %s at %g fps\n", scene.name.c_str(), scene.path.c_str(),
                    counted(whole("characters", world.character_count), "character").c_str(),
                    counted(world.chains.size(), "chain").c_str(), counted(world.joint_count, "joint").c_str(),
                    part ? " in this shard" : "", counted(sim.frame_count(), "frame").c_str(), static_cast<double>(rods->fps));
    }
    std::fflush(stdout);
}

// "ms per frame" is the steady cost: the first call into a backend (frame 0 of the
// chains: load, rest shapes, kernels compiled; the first chunk of the birds) is printed
// apart, since lavapipe compiles a pipeline at its first dispatch and a short run would
// otherwise report mostly that (docs/command-line.md, "Timing").
void print_timing(const Simulation& sim) {
    const BirdTiming& timing = bird_timing(sim);
    const ChainTiming& chain = chain_timing(sim);
    const std::string backend(backend_name(sim.backend()));
    // Only a Vulkan backend compiles kernels at its first call; the CPU ones have nothing
    // to compile, and since auto takes cpu on lavapipe the label must not say they do.
    const bool compiles = sim.backend() == BackendKind::Vulkan;
    if (!bird_world(sim).birds.empty()) {
        const bool steady = timing.frames > 0;
        const double seconds = steady ? timing.seconds : timing.first_seconds;
        const double frames = static_cast<double>(steady ? timing.frames : timing.first_frames);
        const double gpu_ms = steady ? (timing.gpu_timed ? timing.gpu_ms : -1.0) : timing.first_gpu_ms;
        std::printf("kodawari: backend %s on %s: %.3f ms per frame", backend.c_str(), sim.device().c_str(),
                    1e3 * seconds / frames);
        if (gpu_ms >= 0.0) std::printf(" (GPU %.3f ms)", gpu_ms / frames);
        std::printf(", %.3g bird-frames/s", static_cast<double>(bird_world(sim).birds.size()) * frames / std::max(seconds, 1e-9));
        if (steady) {
            std::printf("; first %llu frames %.1f ms%s\n", static_cast<unsigned long long>(timing.first_frames),
                        1e3 * timing.first_seconds, compiles ? " (kernels compiled)" : "");
        } else {
            std::printf(" (one call%s)\n", compiles ? ": kernel compilation included" : "");
        }
    }
    if (const RodScene* rods = rod_scene(sim)) {
        const std::uint32_t frames = sim.frame_count();
        const std::string input = rod_inputs_on_device(sim) ? "; rigged characters' rod input written on the device" : "";
        if (frames <= 2) {
            std::printf("kodawari: backend %s on %s: %u frames in %.1f ms (load, rest shapes%s: too few frames for a steady "
                        "figure)%s\n",
                        backend.c_str(), sim.device().c_str(), frames, 1e3 * chain.warmup_seconds,
                        compiles ? ", kernels compiled" : "", input.c_str());
            return;
        }
        const std::uint32_t steps = frames - 2;
        std::printf("kodawari: backend %s on %s: %.3f ms per frame", backend.c_str(), sim.device().c_str(),
                    1e3 * chain.seconds / steps);
        if (chain.gpu_ms > 0.0) std::printf(" (GPU %.3f ms)", chain.gpu_ms / steps);
        std::printf(", %.3g joint-steps/s; frames 0-1 %.1f ms (load, rest shapes%s)%s\n",
                    static_cast<double>(rods->world.joint_count) * steps / std::max(chain.seconds, 1e-9),
                    1e3 * chain.warmup_seconds, compiles ? ", kernels compiled" : "", input.c_str());
    }
}

void print_shard(const ShardInfo& info, const std::string& what) {
    std::string parts;
    for (const ShardPart& part : info.parts) {
        parts += (parts.empty() ? "" : ", ") + part.instances + " [" + std::to_string(part.range.begin) + ", " +
                 std::to_string(part.range.end) + ") of " + std::to_string(part.scene_count);
    }
    std::printf("kodawari: %s: %s\n", what.c_str(), parts.c_str());
}

Shard parse_shard(const std::string& text) {
    const auto slash = text.find('/');
    const auto number = [&](const std::string& part) -> std::uint64_t {
        if (part.empty() || part.size() > 6 || part.find_first_not_of("0123456789") != std::string::npos) {
            throw UsageError{"--shard: expected I/N with 0 <= I < N <= 100000 (shard I of N), got \"" + text + "\""};
        }
        return std::stoull(part);
    };
    if (slash == std::string::npos) number("");
    const std::uint64_t index = number(text.substr(0, slash));
    const std::uint64_t count = number(text.substr(slash + 1));
    if (count == 0 || count > 100000 || index >= count) {
        throw UsageError{"--shard: expected I/N with 0 <= I < N <= 100000 (shard I of N), got \"" + text + "\""};
    }
    return {static_cast<std::uint32_t>(index), static_cast<std::uint32_t>(count)};
}

// `run --mpi`: one shard per rank, rank 0 writes (kodawari/simulation/distributed.hpp).
int run_distributed(const std::string& scene_path, const BackendChoice& choice, std::optional<std::uint64_t> frames,
                    const std::optional<std::string>& out, const std::optional<std::string>& trace, bool no_export,
                    const GlbCompaction& compaction, bool strict, bool fit_routes) {
#ifdef KODAWARI_WITH_MPI
    auto job = open_mpi_world();
    if (!job) return report(job.error());
    Communicator& comm = *job.value();
    const bool root = comm.rank() == 0;
    DistributedBakeOptions options;
    options.simulation.backend = choice.backend;
    options.simulation.options = choice.options;
    if (frames) options.simulation.frames = static_cast<std::uint32_t>(*frames);
    const Simulation* opened = nullptr;
    // --strict and --fit-routes: every rank checks (and fits) the scene it loaded, the
    // same way since the fit is a function of the scene; rank 0 alone says what it found.
    options.prepare_scene = [&](Scene& scene) -> Result<void> {
        // Never over a file the scene reads (every rank decides alike; rank 0 says it).
        if (!no_export) {
            const std::string glb = out ? *out : "out/" + scene.name + ".glb";
            KW_TRY(refuse_overwriting_inputs(scene, glb_bake_paths(glb, !scene.flocks.empty(), !scene.characters.empty()),
                                             out ? "--out" : "the default output", ".glb"));
        }
        if (trace) KW_TRY(refuse_overwriting_inputs(scene, {*trace}, "--trace", ".jsonl"));
        const auto stop = check_scene_routes(scene, strict, fit_routes, root);
        if (!stop) return {};
        return make_error(*stop == kExitBadInput ? Error::Kind::InvalidInput : Error::Kind::Internal,
                          "the route check stopped the bake (said above)");
    };
    options.opened = [&](const Simulation& sim) {
        opened = &sim;
        if (!root) return;
        print_scene(sim);
        print_shard(sim.shard(), "rank 0 of " + std::to_string(comm.size()) + " (one shard per rank)");
        std::fflush(stdout);
    };
    options.make_sinks = [&](const BakeWorld& world) {
        std::vector<std::unique_ptr<BakeSink>> sinks;
        if (!no_export) {
            sinks = glb_sinks(out ? *out : default_output(world.scene->name), !bird_world_of(world).birds.empty(),
                              rod_scene_of(world) != nullptr, compaction);
        }
        if (trace) sinks.push_back(make_trace_sink(*trace));
        return sinks;
    };
    options.bake.simulated = [&]() -> Result<void> {
        if (root) print_timing(*opened);
        if (opened->validation_messages() > 0) {
            return make_error(Error::Kind::Vulkan, "Vulkan validation reported " + std::to_string(opened->validation_messages()) +
                                                       " messages");
        }
        return {};
    };
    if (root && stderr_is_terminal()) {
        options.bake.progress = [](std::uint32_t done, std::uint32_t total) { progress("simulating", done, total); };
    }
    // Rank 0 writes, so it makes the outputs' folders as a single process does; when it
    // cannot, its sink fails, and bake_distributed stops every rank with that error.
    if (root) {
        for (const auto& [path, option] : {std::pair{out, "--out"}, std::pair{trace, "--trace"}}) {
            if (path) (void)make_parent_folder(*path, option);
        }
    }
    auto written = bake_distributed(comm, scene_path, options);
    // Every rank has the same error; rank 0 says it.
    if (!written) return root ? report(written.error()) : (written.error().kind == Error::Kind::InvalidInput ? kExitBadInput : kExitFailure);
    for (const BakeOutput& file : written.value()) print_wrote(file);
    return kExitOk;
#else
    (void)scene_path, (void)choice, (void)frames, (void)out, (void)trace, (void)no_export, (void)compaction, (void)strict,
        (void)fit_routes;
    return report(make_error(Error::Kind::Unsupported,
                             "--mpi: this kodawari was built without MPI (bash scripts/setup installs OpenMPI; then rebuild)"));
#endif
}

struct RunOptions {
    std::optional<std::string> scene;
    BackendFlags backend;
    LodFlags lod;
    std::optional<std::uint64_t> frames;
    std::optional<std::string> out;
    bool no_export = false;
    std::optional<std::string> trace;
    std::optional<std::string> shard;
    std::optional<std::string> compact;
    bool meshopt = false;
    bool mpi = false;
    bool strict = false;
    bool fit_routes = false;
};

int cmd_run(const RunOptions& o) {
    const BackendChoice choice = read_backend_choice(o.backend);
    const auto& frames_option = o.frames;
    const auto& out_option = o.out;
    const bool no_export = o.no_export;
    const auto& trace_path = o.trace;
    const auto& shard_option = o.shard;
    GlbCompaction compaction = read_compaction(o.compact, o.meshopt);
    compaction.threads = choice.options.threads;  // --threads bounds the encoder too
    const bool mpi = o.mpi;
    const std::string scene_path = scene_or_default(o.scene);
    if (mpi && shard_option) throw UsageError{"--mpi and --shard exclude each other (--mpi runs one shard per rank)"};
    if (no_export && out_option) throw UsageError{"--out and --no-export exclude each other"};
    if (no_export && compaction.enabled) throw UsageError{"--compact and --no-export exclude each other"};
    // A part keeps every key: compacting a shard's keys apart would make the merged file
    // depend on N, so compaction happens once, at merge, over the joined keys.
    if (shard_option && compaction.enabled) {
        throw UsageError{"--shard writes a part file with every key, and compaction happens at merge: give --compact to "
                         "`kodawari merge` instead"};
    }
    if (!shard_option) require_glb_name(out_option);  // a part file is a .kwpart
    if (mpi) {
        return run_distributed(scene_path, choice, frames_option, out_option, trace_path, no_export, compaction, o.strict,
                               o.fit_routes);
    }
    if (shard_option && (no_export || trace_path)) {
        throw UsageError{"--shard writes a part file for `kodawari merge` (at --out): it takes neither --no-export nor --trace"};
    }
    const Shard shard = shard_option ? parse_shard(*shard_option) : Shard{};
    auto loaded = load_scene(scene_path);
    if (!loaded) return report(loaded.error());
    Scene checked = std::move(loaded).value();
    apply_lod(o.lod, checked);
    // Before anything is written: under --strict a route the birds cannot fly stops here.
    if (auto stop = check_scene_routes(checked, o.strict, o.fit_routes)) return *stop;
    auto opened = make_simulation(std::move(checked), choice, frames_option, shard);
    if (!opened) return report(opened.error());
    Simulation& sim = *opened.value();
    const Scene& scene = sim.scene();
    const bool has_birds = !bird_world(sim).birds.empty();
    const bool has_chains = rod_scene(sim) != nullptr;
    // Never over a file the scene reads (a bird's model named as the scene is, in out/).
    // (default_output makes out/: not under --no-export, which writes nothing.)
    const std::string glb = out_option ? *out_option
                            : no_export    ? std::string()
                            : shard_option ? default_output(scene.name, ".shard-" + std::to_string(shard.index) + "-of-" +
                                                                          std::to_string(shard.count) + ".kwpart")
                                           : default_output(scene.name);
    const std::string glb_option = out_option ? "--out" : "the default output";
    if (!no_export) {
        const auto files = shard_option ? std::vector<std::string>{glb} : glb_bake_paths(glb, has_birds, has_chains);
        if (auto refused = refuse_overwriting_inputs(scene, files, glb_option, shard_option ? ".kwpart" : ".glb"); !refused) {
            return report(refused.error());
        }
    }
    if (trace_path) {
        if (auto refused = refuse_overwriting_inputs(scene, {*trace_path}, "--trace", ".jsonl"); !refused) return report(refused.error());
        // Two outputs in one file: whichever finished last would be left.
        for (const std::string& file : no_export ? std::vector<std::string>{} : glb_bake_paths(glb, has_birds, has_chains)) {
            if (same_file(*trace_path, file)) throw UsageError{"--trace " + *trace_path + " is also " + (file == glb ? "--out" : "the characters' file beside --out") + "; give it a path of its own"};
        }
    }
    // The outputs' folders, made before the simulation runs (as render makes its --out).
    for (const auto& [path, option] : {std::pair{out_option, "--out"}, std::pair{trace_path, "--trace"}}) {
        if (!path) continue;
        if (auto made = make_parent_folder(*path, option); !made) return report(made.error());
    }
    std::vector<std::unique_ptr<BakeSink>> owned;
    if (shard_option) {
        owned.push_back(make_part_sink(glb, sim));
    } else if (!no_export) {
        owned = glb_sinks(glb, has_birds, has_chains, compaction);
    }
    if (trace_path) owned.push_back(make_trace_sink(*trace_path));

    print_scene(sim);
    if (shard_option) print_shard(sim.shard(), "shard " + std::to_string(shard.index) + " of " + std::to_string(shard.count));
    const std::size_t per_frame = bird_world(sim).birds.size() + (has_chains ? rod_scene(sim)->world.joint_count : 0);
    BakeOptions options;
    if (stderr_is_terminal() && std::uint64_t{sim.frame_count()} * per_frame >= 2'000'000) {
        options.progress = [](std::uint32_t done, std::uint32_t total) { progress("simulating", done, total); };
    }
    options.simulated = [&sim]() -> Result<void> {
        print_timing(sim);
        // Validation has said why already: an empty message tells cmd_run not to repeat it.
        if (validation_failed(sim.validation_messages())) return make_error(Error::Kind::Vulkan, "");
        return {};
    };
    auto written = bake(sim, sink_pointers(owned), options);
    if (!written) return written.error().message.empty() ? kExitFailure : report(written.error());
    for (const BakeOutput& file : written.value()) print_wrote(file);
    return kExitOk;
}

}  // namespace

Command add_run(CLI::App& app) {
    auto o = std::make_shared<RunOptions>();
    CLI::App* c = app.add_subcommand("run", "simulate a scene and bake it to glTF (docs/command-line.md)");
    add_scene(*c, o->scene);
    add_count(*c, "--frames", o->frames, 1, kMaxSimulationFrames, "frames to simulate (default: the scene's)");
    add_text(*c, "--out", o->out, "FILE.glb",
             "the glTF file (default: out/<scene>.glb; with --shard out/<scene>.shard-I-of-N.kwpart)");
    add_switch(*c, "--no-export", o->no_export, "simulate (and trace) without writing glTF");
    add_compaction_option(*c, o->compact, o->meshopt);
    add_text(*c, "--trace", o->trace, "FILE.jsonl", "also write every frame's state as JSON Lines (default: none)");
    add_text(*c, "--shard", o->shard, "I/N", "simulate only shard I of N and write a part file for `kodawari merge` (default: all)");
    add_switch(*c, "--mpi", o->mpi, "under mpirun: one shard per rank, rank 0 writes (default: off)");
    add_route_check_options(*c, o->strict, o->fit_routes);
    add_backend_options(*c, o->backend);
    add_lod_options(*c, o->lod);
    return {c, [o] { return cmd_run(*o); }};
}

}  // namespace kodawari::cli
