#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "commands.hpp"
#include "kodawari/export.hpp"
#include "kodawari/scene.hpp"

namespace kodawari::cli {

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

    std::string out_path;
    if (!no_export) {
        out_path = out_option ? *out_option : "out/" + scene.name + ".glb";
        const std::uint64_t bytes = std::uint64_t{frames} * count * sizeof(gpu::BirdPose);
        if (bytes > (6ull << 30)) {
            return report(make_error(Error::Kind::InvalidInput,
                                     "baking " + std::to_string(count) + " birds x " + std::to_string(frames) +
                                         " frames needs " + std::to_string(bytes >> 20) +
                                         " MiB of poses; use --frames or --no-export"));
        }
        if (!out_option) {
            std::error_code ec;
            std::filesystem::create_directories("out", ec);
        }
    }

    auto opened = open_backend(choice);
    if (!opened) return report(opened.error());
    BirdBackend& backend = *opened.value();
    if (auto r = backend.load(world); !r) return report(r.error());

    std::optional<TraceWriter> trace;
    if (trace_path) {
        auto t = TraceWriter::open(*trace_path, {scene.name, world.fps, frames, std::string(backend.name())});
        if (!t) return report(t.error());
        trace.emplace(std::move(t).value());
    }

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

    if (backend.validation_messages() > 0) {
        std::fprintf(stderr, "kodawari: error: Vulkan validation reported %u messages\n", backend.validation_messages());
        return kExitFailure;
    }
    if (trace) {
        if (auto r = trace->finish(); !r) return report(r.error());
        std::printf("kodawari: wrote trace %s\n", trace_path->c_str());
    }
    if (!no_export) {
        if (auto r = write_birds_glb(out_path, world, poses, frames); !r) return report(r.error());
        std::error_code ec;
        const auto size = std::filesystem::file_size(out_path, ec);
        std::printf("kodawari: wrote %s (%.1f MiB, glTF 2.0 binary)\n", out_path.c_str(),
                    ec ? 0.0 : static_cast<double>(size) / (1 << 20));
    }
    return kExitOk;
}

}  // namespace kodawari::cli
