// `kodawari bench view`: a viewer frame's cost, apart from the other benchmarks (which
// time the simulation alone).
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/domains/scene_draw.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/simulation/simulation.hpp"

namespace kodawari::cli {
namespace {

// kodawari bench view: what a viewer frame costs (simulate, then draw offscreen and wait;
// no image read back, no blit) with the simulation's state drawn where it is computed
// (the vulkan backends on the renderer's device, issue 5), against the same device with
// the state read back and uploaded again (what a renderer on its own device must do),
// and against the cpu backends (uploaded). The three run interleaved, 10 frames at a time,
// so that a noisy machine slows them alike.
struct ViewOptions {
    BackendFlags backend;
    std::optional<std::string> scene;
    std::optional<std::uint64_t> frames;
    std::optional<std::string> size;
    std::optional<std::string> json;
};

int bench_view(const ViewOptions& o) {
    BackendChoice choice = read_backend_choice(o.backend);
    check_json_path(o.json);
    const std::uint32_t frames = static_cast<std::uint32_t>(o.frames.value_or(120));
    const auto size = image_size(o.size);  // not bound: a lambda below uses them (clang < 16)
    const auto width = size.first;
    const auto height = size.second;
    const auto& json_path = o.json;
    auto loaded = load_scene(o.scene ? *o.scene : shipped_scene("scenes/crowd.json"));
    if (!loaded) return report(loaded.error());
    const Scene& scene = loaded.value();
    // A renderer per configuration, so that each keeps its simulation's layers set up
    // (show_on) and the interleaving costs nothing; the vulkan ones simulate on it.
    struct Run {
        const char* name;
        BackendKind kind;
        Simulation::DrawSource source;
        std::unique_ptr<render::Renderer> renderer;
        std::unique_ptr<Simulation> sim;
        double seconds = 0.0;
        std::uint64_t read_back_bytes = 0;
    };
    std::vector<Run> runs;
    runs.push_back({"vulkan shared", BackendKind::Vulkan, Simulation::DrawSource::Device, {}, {}});
    runs.push_back({"vulkan readback", BackendKind::Vulkan, Simulation::DrawSource::ReadBack, {}, {}});
    runs.push_back({"cpu", BackendKind::Cpu, Simulation::DrawSource::Device, {}, {}});
    for (Run& run : runs) {
        auto renderer = render::Renderer::create(renderer_options(choice, width, height));
        if (!renderer) return report(renderer.error());
        run.renderer = std::move(renderer).value();
        BackendOptions options = choice.options;
        options.context = run.renderer->device_context();
        // The read-back configuration makes the rigged characters' rod input on the host too.
        auto made = Simulation::create(scene, {.backend = run.kind, .options = options, .frames = 2 + frames,
                                               .device_inputs = run.source == Simulation::DrawSource::Device});
        if (!made) return report(made.error());
        run.sim = std::move(made).value();
        keep_bird_poses(*run.sim, run.source == Simulation::DrawSource::ReadBack);
        if (auto s = run.sim->show_on(*run.renderer); !s) return report(s.error());
    }
    const Simulation& first = *runs.front().sim;
    const std::vector<glm::vec3> grid = kodawari::content_points(rod_scene(first), nullptr, &bird_world(first));
    std::printf("bench view: scene \"%s\": %zu chains, %zu birds, %ux%u, %u frames per configuration after 2 warm-up frames, "
                "interleaved 10 at a time, on %s\n",
                scene.name.c_str(), rod_scene(first) ? rod_scene(first)->world.chains.size() : std::size_t{0},
                bird_world(first).birds.size(), width, height, frames, runs.front().renderer->device().c_str());
    std::fflush(stdout);

    // One frame of a configuration: simulate, give the renderer the state, draw.
    const auto frame = [&](Run& run) -> Result<void> {
        render::Renderer& r = *run.renderer;
        const std::uint64_t before = r.read_back_bytes();
        KW_TRY(run.sim->step());
        KW_TRY(run.sim->draw_on(r, run.source));
        const std::uint32_t f = *run.sim->frame();
        render::DrawList list(kodawari::scene_camera(scene, f), width, height);
        render::add_ground_grid(list, grid);
        if (rod_scene(*run.sim)) kodawari::add_characters(list, *rod_scene(*run.sim), f);
        KW_TRY(r.draw(list));
        if (f >= 2) run.read_back_bytes += r.read_back_bytes() - before;
        return {};
    };
    for (Run& run : runs) {
        for (std::uint32_t f = 0; f < 2; ++f) {
            if (auto s = frame(run); !s) return report(s.error());
        }
    }
    for (std::uint32_t done = 0; done < frames;) {
        const std::uint32_t n = std::min(10u, frames - done);
        for (Run& run : runs) {
            const auto start = std::chrono::steady_clock::now();
            for (std::uint32_t k = 0; k < n; ++k) {
                if (auto s = frame(run); !s) return report(s.error());
            }
            run.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        }
        done += n;
    }
    for (const Run& run : runs) {
        if (validation_failed(run.renderer->validation_messages())) return kExitFailure;
    }
    const double baseline = frames / runs[1].seconds;
    std::printf("\n%-16s %12s %12s %22s %18s\n", "configuration", "frames/s", "ms/frame", "read back B/frame", "vs vulkan readback");
    // "count": the configurations timed, as every bench's JSON has a count and frames.
    std::string json = "{\"benchmark\":\"view\",\"scene\":\"" + json_escape(scene.name) + "\"" +
                       json_size(runs.size(), frames) + ",\"results\":[";
    for (std::size_t i = 0; i < runs.size(); ++i) {
        const Run& run = runs[i];
        const double fps = frames / run.seconds;
        // The cpu backends' state is on the host already: nothing to read back from a device.
        char bytes[32] = "-";
        if (run.kind == BackendKind::Vulkan) std::snprintf(bytes, sizeof bytes, "%.0f", static_cast<double>(run.read_back_bytes) / frames);
        std::printf("%-16s %12.4g %12.3f %22s %17.2fx\n", run.name, fps, 1e3 * run.seconds / frames, bytes, fps / baseline);
        // The same in the JSON: null where the table says '-'.
        char numbers[200];
        std::snprintf(numbers, sizeof numbers, "\"per_second\":%.6g,\"ms_per_frame\":%.6g,\"read_back_bytes_per_frame\":%s", fps,
                      1e3 * run.seconds / frames, run.kind == BackendKind::Vulkan ? bytes : "null");
        json += (i ? "," : "") + std::string("{\"configuration\":\"") + run.name + "\"," + numbers + "}";
    }
    json += "]}\n";
    return json_path ? write_json(*json_path, json) : kExitOk;
}

}  // namespace

CLI::App* add_bench_view(CLI::App& bench, std::function<int()>& run) {
    auto view = std::make_shared<ViewOptions>();
    CLI::App* v = bench.add_subcommand("view", "frames per second drawing a scene as the viewer does, from the simulation's "
                                               "device buffers and read back");
    add_scene(*v, view->scene, "scenes/crowd.json");
    add_count(*v, "--frames", view->frames, 1, 100'000, "frames (default: 120)");
    add_size(*v, view->size, "the offscreen image");
    add_text(*v, "--json", view->json, "FILE.json",
             "also write the results as JSON, to a file in a folder that exists (checked before anything runs; \"-\" is "
             "refused, /dev/stdout writes it after the table; default: none)");
    add_backend_options(*v, view->backend);
    // It times fixed contenders (vulkan drawn where computed, vulkan read back, cpu): a
    // backend choice would be ignored, so the option is not offered.
    v->remove_option(v->get_option("--backend"));
    v->get_option("--threads")->description("the cpu configuration's threads (default: one per hardware thread)");
    // Not the other benchmarks' columns (medians, ratios to the cpu kinds, ISA, threads):
    // one measurement per configuration.
    v->footer("Columns: frames/s and ms/frame over all the timed frames of a configuration (one measurement each, no "
              "repetitions, medians or min and max); read back B/frame, the bytes the renderer read back from the "
              "simulation's device per frame ('-' for cpu, whose state is on the host already); vs vulkan readback, the "
              "frames/s over the vulkan readback configuration's. --json writes the same per configuration "
              "(configuration, per_second, ms_per_frame, read_back_bytes_per_frame: null for cpu) with the scene, count "
              "(the configurations) and frames; docs/performance.md.");
    run = [view] { return bench_view(*view); };
    return v;
}

}  // namespace kodawari::cli
