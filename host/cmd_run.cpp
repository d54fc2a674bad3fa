#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <vector>

#include "commands.hpp"
#include "kodawari/crowd_animator.hpp"
#include "kodawari/export.hpp"
#include "kodawari/rod_scene.hpp"
#include "kodawari/scene.hpp"

namespace kodawari::cli {

namespace {

// Where a run's outputs go and what it reports.
struct RunOutputs {
    bool no_export = false;
    std::string out_path;  // "" when not exporting
    std::optional<TraceWriter>* trace = nullptr;
};

int run_birds(const Scene& scene, birds::BirdWorld& world, const BackendChoice& choice, const std::string& out_path,
              std::optional<TraceWriter>& trace);

int run_chains(const Scene& scene, BackendChoice choice, std::optional<std::uint64_t> frames_option,
               const RunOutputs& outputs) {
    auto built = build_rod_scene(scene);
    if (!built) return report(built.error());
    const RodScene& rods_scene = built.value();
    const rods::RodWorld& world = rods_scene.world;
    const std::uint32_t frames = frames_option ? static_cast<std::uint32_t>(*frames_option) : rods_scene.frames;
    const std::size_t joints = world.joint_count;
    if (!outputs.out_path.empty()) {
        const std::uint64_t bytes = std::uint64_t{frames} * joints * (sizeof(glm::vec3) + sizeof(glm::quat));
        if (bytes > (6ull << 30)) {
            return report(make_error(Error::Kind::InvalidInput, "baking " + std::to_string(joints) + " joints x " +
                                                                    std::to_string(frames) + " frames needs " +
                                                                    std::to_string(bytes >> 20) +
                                                                    " MiB; use --frames or --no-export"));
        }
    }
    share_one_device(choice);
    auto opened = open_rod_backend(choice);
    if (!opened) return report(opened.error());
    RodBackend& backend = *opened.value();
    // Rigged characters' clips are evaluated by the pose backend of the same kind.
    auto animator = CrowdAnimator::create(rods_scene, parse_backend(std::string(backend.name())).value_or(BackendKind::Cpu), choice.options);
    if (!animator) return report(animator.error());
    std::printf("kodawari: scene \"%s\" (%s): %u characters, %zu chains, %zu joints, %u frames at %g fps\n",
                scene.name.c_str(), scene.path.c_str(), world.character_count, world.chains.size(), joints, frames,
                static_cast<double>(rods_scene.fps));
    std::fflush(stdout);

    // Per chain, its character and its index within the character (trace records).
    std::vector<std::uint32_t> characters(world.chains.size()), within(world.chains.size());
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
    std::vector<RiggedCrowdExport> rigged;
    std::vector<std::string> rigged_paths;
    if (!outputs.out_path.empty()) {
        const std::string& out = outputs.out_path;
        const std::string stem = out.substr(0, out.size() - (out.ends_with(".glb") ? 4 : 0));
        for (std::uint32_t k = 0; k < rods_scene.characters.size(); ++k) {
            if (!rods_scene.characters[k].rig) continue;
            auto e = RiggedCrowdExport::create(rods_scene, k);
            if (!e) return report(e.error());
            if (e.value().instances().empty()) continue;
            rigged.push_back(std::move(e).value());
            rigged_paths.push_back(!any_procedural && rods_scene.characters.size() == 1 ? out
                                                                                         : stem + "-" + rods_scene.characters[k].name + ".glb");
        }
    }
    std::vector<glm::vec3> positions(outputs.out_path.empty() || !any_procedural ? 0 : std::size_t{frames} * joints);
    std::vector<glm::quat> orientations(positions.size());
    rods::RodFrame frame;
    ChainSnapshot snapshot;
    const bool show_progress = stderr_is_terminal() && std::uint64_t{frames} * joints >= 2'000'000;
    double seconds = 0.0, gpu_ms = 0.0;
    for (std::uint32_t f = 0; f < frames; ++f) {
        if (auto r = animator.value().frame(f, frame); !r) return report(r.error());
        const auto start = std::chrono::steady_clock::now();
        // Frame 0 is the initial pose; every later frame is one step.
        if (auto r = f == 0 ? backend.load(world, frame) : backend.step(frame); !r) return report(r.error());
        if (f == 0) {
            // From now on the rigged characters' input is written where the chains step.
            if (auto r = animator.value().write_inputs_on(backend); !r) return report(r.error());
        }
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (f > 0 && backend.last_gpu_ms() >= 0.0) gpu_ms += backend.last_gpu_ms();
        if (*outputs.trace || !positions.empty() || !rigged.empty()) {
            if (auto r = backend.read(snapshot); !r) return report(r.error());
        }
        for (RiggedCrowdExport& e : rigged) {
            if (auto r = e.add_frame(f, snapshot); !r) return report(r.error());
        }
        if (*outputs.trace) {
            (*outputs.trace)->write_chains(f, rods_scene.time(f), world, characters, within, rods_scene.chain_names, snapshot);
        }
        if (!positions.empty()) {
            std::copy(snapshot.positions.begin(), snapshot.positions.end(), positions.begin() + static_cast<std::ptrdiff_t>(f * joints));
            std::copy(snapshot.orientations.begin(), snapshot.orientations.end(),
                      orientations.begin() + static_cast<std::ptrdiff_t>(f * joints));
        }
        if (show_progress) progress("simulating", f + 1, frames);
    }
    const std::uint32_t steps = std::max(frames, 2u) - 1;
    std::printf("kodawari: backend %s on %s: %.3f ms per frame", std::string(backend.name()).c_str(), backend.device().c_str(),
                1e3 * seconds / frames);
    if (backend.name() == "vulkan" && gpu_ms > 0.0) std::printf(" (GPU %.3f ms)", gpu_ms / steps);
    std::printf(", %.3g joint-steps/s%s\n", static_cast<double>(joints) * steps / std::max(seconds, 1e-9),
                animator.value().writes_inputs_on_device() ? "; rigged characters' rod input written on the device" : "");
    // One device shared: both count the same messages.
    if (validation_failed(std::max(backend.validation_messages(), animator.value().validation_messages()))) {
        return kExitFailure;
    }
    const auto wrote = [](const std::string& path, const char* what) {
        std::error_code ec;
        const auto size = std::filesystem::file_size(path, ec);
        std::printf("kodawari: wrote %s (%.1f MiB, glTF 2.0 binary%s)\n", path.c_str(), ec ? 0.0 : static_cast<double>(size) / (1 << 20),
                    what);
    };
    for (std::size_t i = 0; i < rigged.size(); ++i) {
        if (auto r = rigged[i].finish(rigged_paths[i]); !r) return report(r.error());
        wrote(rigged_paths[i], ", the character's own skeleton and meshes");
    }
    if (!positions.empty()) {
        if (auto r = write_chains_glb(outputs.out_path, rods_scene, frames, positions, orientations); !r) return report(r.error());
        wrote(outputs.out_path, "");
    }
    return kExitOk;
}

}  // namespace

int cmd_run(Args args) {
    const BackendChoice choice = read_backend_choice(args);
    const auto frames_option = args.count("frames", 1, 10'000'000);
    const auto out_option = args.option("out");
    const bool no_export = args.flag("no-export");
    const auto trace_path = args.option("trace");
    if (no_export && out_option) throw UsageError{"--out and --no-export exclude each other"};
    auto loaded = load_scene_arguments(args.positionals(), "run", frames_option);
    if (!loaded) return report(loaded.error());
    const Scene& scene = loaded.value().scene;
    birds::BirdWorld& world = loaded.value().world;
    const std::uint32_t frames = world.frames;
    const std::size_t count = world.birds.size();
    const bool has_birds = count > 0;
    const bool has_chains = !scene.characters.empty();
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
        auto t = TraceWriter::open(*trace_path, {scene.name, world.fps, frames,
                                                 resolved_backend_name(choice)});
        if (!t) return report(t.error());
        trace.emplace(std::move(t).value());
    }
    if (has_birds) {
        if (const int code = run_birds(scene, world, choice, no_export ? std::string() : base_out, trace); code != kExitOk) {
            return code;
        }
    }
    if (has_chains) {
        if (const int code = run_chains(scene, choice, frames_option, {no_export, chains_out, &trace}); code != kExitOk) {
            return code;
        }
    }
    if (trace) {
        if (auto r = trace->finish(); !r) return report(r.error());
        std::printf("kodawari: wrote trace %s\n", trace_path->c_str());
    }
    return kExitOk;
}

namespace {

int run_birds(const Scene& scene, birds::BirdWorld& world, const BackendChoice& choice, const std::string& out_path,
              std::optional<TraceWriter>& trace) {
    const bool no_export = out_path.empty();
    const std::uint32_t frames = world.frames;
    const std::size_t count = world.birds.size();
    if (!no_export) {
        const std::uint64_t bytes = std::uint64_t{frames} * count * sizeof(gpu::BirdPose);
        if (bytes > (6ull << 30)) {
            return report(make_error(Error::Kind::InvalidInput,
                                     "baking " + std::to_string(count) + " birds x " + std::to_string(frames) +
                                         " frames needs " + std::to_string(bytes >> 20) +
                                         " MiB of poses; use --frames or --no-export"));
        }
    }

    auto opened = open_backend(choice);
    if (!opened) return report(opened.error());
    BirdBackend& backend = *opened.value();
    if (auto r = backend.load(world); !r) return report(r.error());

    std::printf("kodawari: scene \"%s\" (%s): %zu birds, %u frames at %g fps\n", scene.name.c_str(),
                scene.path.c_str(), count, frames, static_cast<double>(world.fps));
    std::fflush(stdout);

    std::vector<gpu::BirdPose> poses(no_export ? 0 : std::size_t{frames} * count);
    // Chunks bound the memory of traces and let the progress bar move.
    const std::uint32_t chunk = static_cast<std::uint32_t>(std::clamp<std::size_t>((1u << 20) / std::max<std::size_t>(count, 1), 1, 120));
    std::vector<gpu::BirdPose> chunk_poses;
    std::vector<gpu::BirdDiag> chunk_diag;
    const bool show_progress = stderr_is_terminal() && std::uint64_t{frames} * count >= 2'000'000;
    double seconds = 0.0, gpu_ms = 0.0;
    bool have_gpu_time = true;
    for (std::uint32_t done = 0; done < frames;) {
        const std::uint32_t n = std::min(chunk, frames - done);
        FrameOutput out;
        if (!no_export) out.poses = std::span(poses).subspan(std::size_t{done} * count, std::size_t{n} * count);
        if (trace) {
            if (no_export) {
                chunk_poses.resize(std::size_t{n} * count);
                out.poses = chunk_poses;
            }
            chunk_diag.resize(std::size_t{n} * count);
            out.diag = chunk_diag;
        }
        const auto start = std::chrono::steady_clock::now();
        if (auto r = backend.simulate(n, out); !r) return report(r.error());
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (backend.last_gpu_ms() >= 0.0) gpu_ms += backend.last_gpu_ms(); else have_gpu_time = false;
        if (trace) {
            for (std::uint32_t k = 0; k < n; ++k) {
                trace->write_frame(done + k, world, out.poses.subspan(std::size_t{k} * count, count),
                                   std::span<const gpu::BirdDiag>(chunk_diag).subspan(std::size_t{k} * count, count));
            }
        }
        done += n;
        if (show_progress) progress("simulating", done, frames);
    }

    std::printf("kodawari: backend %s on %s: %.3f ms per frame", std::string(backend.name()).c_str(), backend.device().c_str(),
                1e3 * seconds / frames);
    if (have_gpu_time && backend.name() == "vulkan") std::printf(" (GPU %.3f ms)", gpu_ms / frames);
    std::printf(", %.3g bird-frames/s\n", static_cast<double>(count) * frames / std::max(seconds, 1e-9));

    if (validation_failed(backend.validation_messages())) return kExitFailure;
    if (!no_export) {
        if (auto r = write_birds_glb(out_path, world, poses, frames); !r) return report(r.error());
        std::error_code ec;
        const auto size = std::filesystem::file_size(out_path, ec);
        std::printf("kodawari: wrote %s (%.1f MiB, glTF 2.0 binary)\n", out_path.c_str(),
                    ec ? 0.0 : static_cast<double>(size) / (1 << 20));
    }
    return kExitOk;
}

}  // namespace

}  // namespace kodawari::cli
