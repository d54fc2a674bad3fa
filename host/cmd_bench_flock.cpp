// kodawari bench flock (issue 32): the flocking step of N birds on every backend, in
// bird-steps per second (birds x substeps / s, Blender's boids and BoidsUnity's unit),
// with the neighbour search's share on every backend (docs/performance.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/domains/flocking.hpp"
#include "kodawari/scene/scene.hpp"

namespace kodawari::cli {

namespace {

struct FlockOptions {
    BenchCommon common;
    std::optional<std::uint64_t> count;
    std::optional<std::uint64_t> frames;
};

// One flocking flock of `count` starling-sized birds, as scenes/starlings.json's (20 000
// birds in a formation box of half sizes 30 x 12 x 30 m) at the same density: the box
// grows with the cube root of the count. 60 frames a second, one substep a frame.
Scene flock_scene(std::uint32_t count, std::uint32_t frames) {
    Scene scene;
    scene.name = "bench-flock";
    scene.path = "(bench)";
    scene.fps = 60.0f;
    scene.duration = static_cast<float>(frames) / scene.fps;
    const float grow = std::cbrt(static_cast<float>(count) / 20000.0f);
    FlockSpec flock;
    flock.name = "starlings";
    flock.wing_type = birds::WingType::Pigeon;
    flock.count = count;
    flock.seed = 1963;
    flock.speed = 15.0f;
    flock.speed_jitter = 0.04f;
    flock.generated_route = GeneratedRouteSpec{.seed = 11, .segments = 8, .center = {0, 50, 0},
                                               .extent = {60 * grow, 10 * grow, 60 * grow}, .loop = true};
    flock.formation = FormationSpec{.spread = {30 * grow, 12 * grow, 30 * grow}};
    flock.flocking = FlockingSpec{};
    scene.flocks.push_back(flock);
    return scene;
}

int bench_flock(const FlockOptions& o) {
    const BackendChoice choice = read_backend_choice(o.common.backend);
    check_json_path(o.common.json);
    const auto count = static_cast<std::uint32_t>(o.count.value_or(1'000'000));
    const auto frames = static_cast<std::uint32_t>(o.frames.value_or(5));
    const std::uint32_t repetitions = read_repetitions(o.common);
    const std::vector<BenchVariant> variants = read_variants(o.common, choice);
    // Frame 0 is the formation; frame 1 warms up (and compiles the kernels).
    const std::uint32_t total = 2 + frames * repetitions;
    const Scene scene = flock_scene(count, total);
    auto world = build_bird_world(scene);
    if (!world) return report(world.error());
    std::printf("bench flock: %u flocking birds (k = 7 nearest in view, search radius 3 m, starlings.json's density), "
                "one substep of 1/60 s a frame; %u repetitions of %u frames per backend, interleaved, after a warm-up "
                "frame; the motion handed to the wingbeats (read back from a device) is part of each frame\n",
                count, repetitions, frames);
    std::fflush(stdout);

    std::vector<std::unique_ptr<Domain>> domains;
    std::vector<std::uint32_t> next;
    std::vector<Contender> contenders;
    std::vector<Skipped> skipped;
    for (const auto& [kind, backend_options, label] : variants) {
        auto made = make_flocking_domain(scene, world.value());
        if (!made) return report(made.error());
        Domain& d = *made.value();
        DomainSetup setup{.kind = kind, .options = backend_options};
        if (auto opened = d.open(setup, {}); !opened) {
            skip(skipped, label, opened.error().message);
            continue;
        }
        if (auto r = d.step(0, 2, {}); !r) return report(r.error());
        const std::size_t index = domains.size();
        domains.push_back(std::move(made).value());
        next.push_back(2);
        Contender c;
        c.measured.backend = label;
        c.measured.device = d.device();
        describe(c.measured, kind, choice.options);
        c.repetition = [&, index, frames](double& gpu_ms) -> Result<double> {
            Domain& dom = *domains[index];
            const double device_before = flocking_timing(dom).device_seconds;
            const auto start = std::chrono::steady_clock::now();
            for (std::uint32_t f = 0; f < frames; ++f) KW_TRY(dom.step(next[index]++, 1, {}));
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            // The device's time of the frames' dispatches, where it has timestamps.
            const double device_after = flocking_timing(dom).device_seconds;
            gpu_ms = device_before < 0.0 || device_after < 0.0 ? -1.0 : 1000.0 * (device_after - device_before);
            return seconds;
        };
        contenders.push_back(std::move(c));
    }
    if (auto r = run_repetitions(contenders, repetitions, frames, static_cast<double>(count)); !r) return report(r.error());
    // Where the time went: the CPU kinds over the warm-up and every repetition, as they
    // ran; vulkan timed apart now (profile_flocking: its step is one submission). In the
    // JSON too (each result's grid_share, search_share, rules_share, search_ns_per_bird).
    std::vector<FlockingTiming> split(contenders.size());
    for (std::size_t i = 0; i < contenders.size(); ++i) {
        split[i] = flocking_timing(*domains[i]);
        if (split[i].grid_seconds + split[i].search_seconds + split[i].rules_seconds <= 0.0) {
            auto profiled = profile_flocking(*domains[i], frames);
            if (profiled) split[i] = profiled.value();
        }
        const FlockingTiming& t = split[i];
        const double sum = t.grid_seconds + t.search_seconds + t.rules_seconds;
        if (sum <= 0.0 || t.bird_steps == 0) continue;
        char extra[200];
        std::snprintf(extra, sizeof extra, ",\"grid_share\":%.4f,\"search_share\":%.4f,\"rules_share\":%.4f,\"search_ns_per_bird\":%.1f",
                      t.grid_seconds / sum, t.search_seconds / sum, t.rules_seconds / sum,
                      1e9 * t.search_seconds / static_cast<double>(t.bird_steps));
        contenders[i].measured.extra_json += extra;
    }
    const int status = report_results(contenders, skipped, "bird-steps/s", repetitions, choice.options,
                                      "{\"benchmark\":\"flock\"" + json_size(count, frames), o.common.json);
    if (contenders.empty()) return status;
    std::printf("\nwhere the time went (cpu kinds: as they ran, the search and the rules in thread-seconds over their "
                "threads; vulkan: %u frames of the grid alone, of the grid and the search, and of the whole step, one "
                "submission each, by the device's timestamps or, without them, the wall clock):\n",
                frames);
    std::printf("%-20s %10s %12s %12s %14s\n", "backend", "grid %", "search %", "rules %", "search ns/bird");
    for (std::size_t i = 0; i < contenders.size(); ++i) {
        const FlockingTiming& t = split[i];
        const double sum = t.grid_seconds + t.search_seconds + t.rules_seconds;
        if (sum <= 0.0 || t.bird_steps == 0) {
            std::printf("%-20s %10s %12s %12s %14s\n", contenders[i].measured.backend.c_str(), "-", "-", "-", "-");
            continue;
        }
        std::printf("%-20s %10.1f %12.1f %12.1f %14.1f\n", contenders[i].measured.backend.c_str(), 100.0 * t.grid_seconds / sum,
                    100.0 * t.search_seconds / sum, 100.0 * t.rules_seconds / sum,
                    1e9 * t.search_seconds / static_cast<double>(t.bird_steps));
    }
    return status;
}

}  // namespace

CLI::App* add_bench_flock(CLI::App& bench, std::function<int()>& run) {
    auto options = std::make_shared<FlockOptions>();
    CLI::App* f = bench.add_subcommand("flock", "bird-steps per second of the flocking step (neighbours, rules, limits) on a "
                                                "flock of N birds");
    add_count(*f, "--count", options->count, 1, 4'000'000, "flocking birds, 1 to 4000000 (default: 1000000)");
    add_count(*f, "--frames", options->frames, 1, 100'000, "frames per repetition (default: 5)");
    add_common(*f, options->common);
    run = [options] { return bench_flock(*options); };
    return f;
}

}  // namespace kodawari::cli
