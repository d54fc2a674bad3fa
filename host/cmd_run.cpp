// `kodawari run SCENE`: bakes a scene (kodawari/bake.hpp) into glTF and optionally a
// JSON Lines trace. Arguments and messages around the engine's bake pipeline.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "kodawari/bake.hpp"
#include "kodawari/rod_scene.hpp"
#include "kodawari/scene.hpp"
#include "kodawari/simulation.hpp"

namespace kodawari::cli {

namespace {

// `--compact[=ERROR]`: ERROR is METRES or METRES,RADIANS (README "Compact files"). One
// number bounds all three kinds as the displacement of a point 1 m from the joint: a
// rotation of E rad, or a scale off by E relative, moves it E m, as a translation error
// of E m does. A second number sets the rotation (and scale) bound on its own.
GlbCompaction read_compaction(Args& args) {
    const auto option = args.flag_or_value("compact");
    GlbCompaction compaction;
    if (!option) return compaction;
    compaction.enabled = true;
    if (!*option) return compaction;
    const std::string& text = **option;
    const auto fail = [&]() -> UsageError {
        return UsageError{"--compact: expected --compact, --compact=METRES or --compact=METRES,RADIANS (numbers >= 0, e.g. "
                          "--compact=0.001 or --compact=0.002,0.005), got \"" + text + "\""};
    };
    const auto number = [&](const std::string& part) {
        char* end = nullptr;
        const double v = part.empty() || part[0] == '-' || part[0] == '+' || std::isspace(static_cast<unsigned char>(part[0]))
                             ? -1.0
                             : std::strtod(part.c_str(), &end);
        if (end == nullptr || *end != '\0' || !std::isfinite(v) || v < 0.0 || v > 1e6) throw fail();
        return static_cast<float>(v);
    };
    const std::size_t comma = text.find(',');
    compaction.position_m = number(text.substr(0, comma));
    compaction.rotation_rad = comma == std::string::npos ? compaction.position_m : number(text.substr(comma + 1));
    compaction.scale_rel = compaction.rotation_rad;
    return compaction;
}

void print_compaction(const GlbCompactionStats& s) {
    const auto size = [](std::uint64_t bytes) {
        char text[32];
        const double b = static_cast<double>(bytes);
        if (bytes >= (1u << 20)) {
            std::snprintf(text, sizeof text, "%.1f MiB", b / (1 << 20));
        } else {
            std::snprintf(text, sizeof text, "%.1f KiB", b / (1 << 10));
        }
        return std::string(text);
    };
    std::printf("kodawari:   compact: %llu of %llu keys kept (%.1f%%), animation data %s -> %s (%.1fx); "
                "largest error %.4g mm, %.4g mrad",
                static_cast<unsigned long long>(s.kept), static_cast<unsigned long long>(s.keys),
                s.keys > 0 ? 100.0 * static_cast<double>(s.kept) / static_cast<double>(s.keys) : 100.0,
                size(s.bytes_before).c_str(), size(s.bytes_after).c_str(),
                s.bytes_after > 0 ? static_cast<double>(s.bytes_before) / static_cast<double>(s.bytes_after) : 1.0,
                1e3 * s.position_m, 1e3 * s.rotation_rad);
    if (s.scale_rel > 0.0) std::printf(", scale %.4g%%", 100.0 * s.scale_rel);
    std::printf("\n");
}

void print_wrote(const BakeOutput& file) {
    if (file.format == BakeOutput::Format::Trace) {
        std::printf("kodawari: wrote trace %s\n", file.path.c_str());
        return;
    }
    std::error_code ec;
    const auto size = std::filesystem::file_size(file.path, ec);
    std::printf("kodawari: wrote %s (%.1f MiB, glTF 2.0 binary%s%s)\n", file.path.c_str(),
                ec ? 0.0 : static_cast<double>(size) / (1 << 20), file.description.empty() ? "" : ", ",
                file.description.c_str());
    if (file.compaction) print_compaction(*file.compaction);
}

void print_scene(const Simulation& sim) {
    const Scene& scene = sim.scene();
    if (!sim.bird_world().birds.empty()) {
        std::printf("kodawari: scene \"%s\" (%s): %zu birds, %u frames at %g fps\n", scene.name.c_str(), scene.path.c_str(),
                    sim.bird_world().birds.size(), sim.frame_count(), static_cast<double>(sim.bird_world().fps));
    }
    if (const RodScene* rods = sim.rod_scene()) {
        const rods::RodWorld& world = rods->world;
        std::printf("kodawari: scene \"%s\" (%s): %u characters, %zu chains, %zu joints, %u frames at %g fps\n",
                    scene.name.c_str(), scene.path.c_str(), world.character_count, world.chains.size(),
                    std::size_t{world.joint_count}, sim.frame_count(), static_cast<double>(rods->fps));
    }
    std::fflush(stdout);
}

void print_timing(const Simulation& sim) {
    const SimulationTiming& timing = sim.timing();
    const std::uint32_t frames = sim.frame_count();
    const std::string backend(backend_name(sim.backend()));
    if (!sim.bird_world().birds.empty()) {
        std::printf("kodawari: backend %s on %s: %.3f ms per frame", backend.c_str(), sim.device().c_str(),
                    1e3 * timing.bird_seconds / frames);
        if (timing.bird_gpu_timed) std::printf(" (GPU %.3f ms)", timing.bird_gpu_ms / frames);
        std::printf(", %.3g bird-frames/s\n",
                    static_cast<double>(sim.bird_world().birds.size()) * frames / std::max(timing.bird_seconds, 1e-9));
    }
    if (const RodScene* rods = sim.rod_scene()) {
        const std::uint32_t steps = std::max(frames, 2u) - 1;
        std::printf("kodawari: backend %s on %s: %.3f ms per frame", backend.c_str(), sim.device().c_str(),
                    1e3 * timing.chain_seconds / frames);
        if (timing.chain_gpu_ms > 0.0) std::printf(" (GPU %.3f ms)", timing.chain_gpu_ms / steps);
        std::printf(", %.3g joint-steps/s%s\n",
                    static_cast<double>(rods->world.joint_count) * steps / std::max(timing.chain_seconds, 1e-9),
                    sim.rod_inputs_on_device() ? "; rigged characters' rod input written on the device" : "");
    }
}

}  // namespace

int cmd_run(Args args) {
    const BackendChoice choice = read_backend_choice(args);
    const auto frames_option = args.count("frames", 1, 10'000'000);
    const auto out_option = args.option("out");
    const bool no_export = args.flag("no-export");
    const auto trace_path = args.option("trace");
    const GlbCompaction compaction = read_compaction(args);
    if (no_export && out_option) throw UsageError{"--out and --no-export exclude each other"};
    if (no_export && compaction.enabled) throw UsageError{"--compact and --no-export exclude each other"};
    auto opened = open_simulation(scene_argument(args.positionals(), "run"), choice, frames_option);
    if (!opened) return report(opened.error());
    Simulation& sim = *opened.value();
    const Scene& scene = sim.scene();
    const bool has_birds = !sim.bird_world().birds.empty();
    const bool has_chains = sim.rod_scene() != nullptr;
    if (!no_export && !out_option) {
        std::error_code ec;
        std::filesystem::create_directories("out", ec);
    }
    // One file per kind of content; a scene with both writes <out> for the birds and
    // <out without .glb>-characters.glb for the characters.
    const std::string base_out = out_option ? *out_option : "out/" + scene.name + ".glb";
    std::vector<std::unique_ptr<BakeSink>> owned;
    if (!no_export && has_birds) owned.push_back(make_birds_glb_sink(base_out));
    if (!no_export && has_chains) {
        owned.push_back(make_chains_glb_sink(
            has_birds ? base_out.substr(0, base_out.size() - (base_out.ends_with(".glb") ? 4 : 0)) + "-characters.glb" : base_out,
            compaction));
    }
    if (trace_path) owned.push_back(make_trace_sink(*trace_path));
    std::vector<BakeSink*> sinks;
    for (const auto& sink : owned) sinks.push_back(sink.get());

    print_scene(sim);
    const std::size_t per_frame = sim.bird_world().birds.size() + (has_chains ? sim.rod_scene()->world.joint_count : 0);
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
    auto written = bake(sim, sinks, options);
    if (!written) return written.error().message.empty() ? kExitFailure : report(written.error());
    for (const BakeOutput& file : written.value()) print_wrote(file);
    return kExitOk;
}

}  // namespace kodawari::cli
