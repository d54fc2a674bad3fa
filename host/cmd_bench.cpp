#include <algorithm>
#include <chrono>
#include <optional>
#include <cstdio>
#include <sstream>
#include <vector>

#include "commands.hpp"
#include "kodawari/atomic_file.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/render/scene_draw.hpp"
#include "kodawari/rod_backend.hpp"
#include "kodawari/rod_scene.hpp"
#include "kodawari/rods/synthetic.hpp"
#include "kodawari/scene.hpp"
#include "kodawari/simulation.hpp"

namespace kodawari::cli {
namespace {

// The benchmark flock: the three wing types in equal shares over generated looping
// routes with 16 variants each, birds spread and staggered so modes and phases differ.
Scene bench_scene(std::uint32_t count, std::uint32_t frames) {
    Scene scene;
    scene.name = "bench-birds";
    scene.path = "(bench)";
    scene.fps = 60.0f;
    scene.duration = static_cast<float>(frames) / scene.fps;
    const birds::WingType types[3] = {birds::WingType::Pigeon, birds::WingType::Gull, birds::WingType::Hawk};
    for (std::uint32_t t = 0; t < 3; ++t) {
        FlockSpec flock;
        flock.name = std::string(birds::wing_type_spec(types[t]).name);
        flock.wing_type = types[t];
        flock.count = count / 3 + (t < count % 3 ? 1 : 0);
        if (flock.count == 0) continue;
        flock.seed = 100 + t;
        flock.speed_jitter = 0.1f;
        flock.frequency_jitter = 0.1f;
        flock.amplitude_jitter = 0.1f;
        flock.generated_route = GeneratedRouteSpec{.seed = 7 + t, .segments = 8, .center = {0, 60, 0}, .extent = {300, 50, 300}, .loop = true};
        flock.formation = FormationSpec{.spread = {20, 8, 20}, .route_variants = 16, .jitter = 10, .trail = 20};
        scene.flocks.push_back(flock);
    }
    return scene;
}

struct Measured {
    std::string backend, device;
    double per_second = 0, ms_per_frame = 0, gpu_ms_per_frame = -1;
};

std::string json_escape(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (c == '"' || c == '\\') out += '\\';
        if (static_cast<unsigned char>(c) >= 0x20) out += c;
    }
    return out;
}

std::vector<BackendKind> read_backends(Args& args) {
    std::vector<BackendKind> kinds;
    std::stringstream names(args.option("backends").value_or("cpu-reference,cpu,vulkan"));
    for (std::string name; std::getline(names, name, ',');) {
        auto kind = parse_backend_choice(name);
        if (!kind || !kind.value()) throw UsageError{"--backends: unknown backend \"" + name + "\""};
        kinds.push_back(*kind.value());
    }
    return kinds;
}

// The table and the --json file, the same shape for every benchmark.
// Writes a benchmark's JSON atomically and says so.
int write_json(const std::string& path, const std::string& text) {
    auto file = AtomicFile::open(path);
    if (!file) return report(file.error());
    file.value().write(text);
    if (auto r = file.value().commit(); !r) return report(r.error());
    std::printf("wrote %s\n", path.c_str());
    return kExitOk;
}

int report_results(const std::vector<Measured>& results, const char* unit, const std::string& json_head,
                   const std::optional<std::string>& json_path) {
    double reference = 0.0;
    for (const auto& m : results) {
        if (m.backend == "cpu-reference") reference = m.per_second;
    }
    std::printf("\n%-14s %-40s %16s %12s %12s %16s\n", "backend", "device", unit, "ms/frame", "GPU ms/frame", "vs cpu-reference");
    for (const auto& m : results) {
        char gpu[32] = "-";
        if (m.gpu_ms_per_frame >= 0.0) std::snprintf(gpu, sizeof gpu, "%.3f", m.gpu_ms_per_frame);
        char ratio[32] = "-";
        if (reference > 0.0) std::snprintf(ratio, sizeof ratio, "%.2fx", m.per_second / reference);
        std::printf("%-14s %-40s %16.4g %12.3f %12s %16s\n", m.backend.c_str(), m.device.c_str(), m.per_second, m.ms_per_frame, gpu,
                    ratio);
    }
    if (json_path) {
        std::string text = json_head + ",\"results\":[";
        for (std::size_t i = 0; i < results.size(); ++i) {
            const auto& m = results[i];
            char numbers[160];
            std::snprintf(numbers, sizeof numbers, "\"per_second\":%.6g,\"ms_per_frame\":%.6g", m.per_second, m.ms_per_frame);
            text += (i ? "," : "") + std::string("{\"backend\":\"") + m.backend + "\",\"device\":\"" + json_escape(m.device) + "\"," +
                    numbers + "}";
        }
        text += "]}\n";
        return write_json(*json_path, text);
    }
    return kExitOk;
}

// kodawari bench chains: every backend on the same procedural chains (rods/synthetic.hpp),
// one solver substep per step, joint-steps per second = chains x joints x steps / s.
int bench_chains(Args& args, const BackendChoice& choice) {
    rods::SyntheticOptions options;
    options.chains = static_cast<std::uint32_t>(args.count("chains", 1, 2'000'000).value_or(100'000));
    options.joints = static_cast<std::uint32_t>(args.count("joints", 2, rods::kMaxChainJoints).value_or(16));
    options.iterations = static_cast<std::uint32_t>(args.count("iterations", 1, 64).value_or(4));
    const std::uint32_t steps = static_cast<std::uint32_t>(args.count("steps", 1, 100'000).value_or(20));
    const auto json_path = args.option("json");
    const std::vector<BackendKind> kinds = read_backends(args);
    if (args.positionals().size() != 1) throw UsageError{"usage: kodawari bench chains [options]"};
    auto made = rods::SyntheticScene::make(options);
    if (!made) return report(made.error());
    const rods::SyntheticScene& scene = made.value();
    const float dt = rods::SolverParams{}.max_substep;  // one substep per step
    std::printf("bench chains: %u chains x %u joints, %u iterations, %u view examples, a head collider each; %u steps of "
                "1/120 s after 1 warm-up step per backend (it also compiles the kernel)\n",
                options.chains, options.joints, options.iterations, options.views, steps);
    std::fflush(stdout);
    // The kinematic input of every step, made before timing: it is the caller's work.
    std::vector<rods::RodFrame> frames(steps + 2);
    for (std::uint32_t f = 0; f < frames.size(); ++f) scene.frame(f, dt, frames[f]);

    std::vector<Measured> results;
    for (BackendKind kind : kinds) {
        auto backend = make_rod_backend(kind, choice.options);
        if (!backend) {
            std::printf("  %-14s skipped: %s\n", std::string(backend_name(kind)).c_str(), backend.error().message.c_str());
            continue;
        }
        RodBackend& b = *backend.value();
        if (auto r = b.load(scene.world(), frames[0]); !r) return report(r.error());
        if (auto r = b.step(frames[1]); !r) return report(r.error());
        double gpu_ms = 0.0;
        const auto start = std::chrono::steady_clock::now();
        for (std::uint32_t f = 0; f < steps; ++f) {
            if (auto r = b.step(frames[f + 2]); !r) return report(r.error());
            gpu_ms += b.last_gpu_ms();
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        Measured m{std::string(b.name()), b.device(),
                   static_cast<double>(options.chains) * options.joints * steps / seconds, 1e3 * seconds / steps,
                   b.last_gpu_ms() >= 0.0 ? gpu_ms / steps : -1.0};
        if (validation_failed(b.validation_messages())) return kExitFailure;
        results.push_back(m);
        std::printf("  %-14s done: %.3g joint-steps/s\n", m.backend.c_str(), m.per_second);
        std::fflush(stdout);
    }
    const std::string head = "{\"benchmark\":\"chains\",\"chains\":" + std::to_string(options.chains) +
                             ",\"joints\":" + std::to_string(options.joints) + ",\"iterations\":" +
                             std::to_string(options.iterations) + ",\"steps\":" + std::to_string(steps);
    return report_results(results, "joint-steps/s", head, json_path);
}


// kodawari bench crowd: every backend on the same crowd of skinned (rigged glTF)
// characters: per frame the clips of every instance (the pose backend of that kind) and
// the chains' step (the rod backend of that kind). Frames per second of the two together.
int bench_crowd(Args& args, const BackendChoice& choice) {
    const std::uint32_t count = static_cast<std::uint32_t>(args.count("count", 1, 100'000).value_or(1000));
    const std::uint32_t frames = static_cast<std::uint32_t>(args.count("frames", 1, 100'000).value_or(60));
    const auto json_path = args.option("json");
    const std::vector<BackendKind> kinds = read_backends(args);
    const auto positionals = args.positionals();
    if (positionals.size() > 2) throw UsageError{"usage: kodawari bench crowd [SCENE] [options]"};
    const std::string path = positionals.size() == 2 ? positionals[1] : "scenes/crowd-gltf.json";
    auto loaded = load_scene(path);
    if (!loaded) return report(loaded.error());
    Scene scene = std::move(loaded).value();
    const auto rigged = std::find_if(scene.crowds.begin(), scene.crowds.end(),
                                     [&](const CrowdSpec& c) { return scene.characters[c.character].rig.has_value(); });
    if (rigged == scene.crowds.end()) {
        return report(make_error(Error::Kind::InvalidInput, path + ": bench crowd needs a crowd of a rigged (glTF) character"));
    }
    CrowdSpec crowd = *rigged;
    crowd.count = count;
    crowd.instances.clear();
    scene.crowds = {crowd};
    // The scene as each backend's Simulation builds it, for the header line.
    auto built = build_rod_scene(scene);
    if (!built) return report(built.error());
    const RodScene& rods_scene = built.value();
    const gltf::Character& character = *rods_scene.characters[crowd.character].rig;
    std::printf("bench crowd: %u instances of %s (%zu nodes, %zu clips), %zu chains, %u joints; %u frames at %g fps after 2 "
                "warm-up frames per backend (they also compile the kernels)\n",
                count, character.source.c_str(), character.nodes.size(), character.animations.size(),
                rods_scene.world.chains.size(), rods_scene.world.joint_count, frames, static_cast<double>(rods_scene.fps));
    std::fflush(stdout);

    std::vector<Measured> results;
    // Vulkan twice: the pose matrices read back and the rod input made on the host, then
    // (one device for both backends) the rod input written on the device.
    struct Variant {
        BackendKind kind;
        bool device_input;
    };
    std::vector<Variant> variants;
    for (BackendKind kind : kinds) {
        variants.push_back({kind, false});
        if (kind == BackendKind::Vulkan) variants.push_back({kind, true});
    }
    for (const auto [kind, device_input] : variants) {
        // Frame 0 (load) and 2 warm-up steps, then the timed frames.
        auto made = Simulation::create(scene, {.backend = kind, .options = choice.options, .frames = frames + 3,
                                               .rod_inputs_on_device = device_input});
        if (!made) {
            std::printf("  %-14s skipped: %s\n", std::string(backend_name(kind)).c_str(), made.error().message.c_str());
            continue;
        }
        Simulation& sim = *made.value();
        if (auto r = sim.step(3); !r) return report(r.error());
        if (device_input && !sim.rod_inputs_on_device()) {
            return report(make_error(Error::Kind::Internal, "the rod input could not go on the device"));
        }
        const SimulationTiming before = sim.timing();
        const auto start = std::chrono::steady_clock::now();
        for (std::uint32_t f = 0; f < frames; ++f) {
            if (auto r = sim.step(); !r) return report(r.error());
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (validation_failed(sim.validation_messages())) return kExitFailure;
        const double pose_ms = sim.timing().pose_ms - before.pose_ms;
        const double gpu_ms = sim.timing().chain_gpu_ms - before.chain_gpu_ms;
        Measured m{std::string(backend_name(kind)) + (kind == BackendKind::Vulkan ? (device_input ? "/dev-in" : "/host-in") : ""),
                   sim.device(), frames / seconds, 1e3 * seconds / frames, gpu_ms > 0.0 ? gpu_ms / frames : -1.0};
        results.push_back(m);
        std::printf("  %-14s done: %.3g frames/s (clips %.3f ms + chains %.3f ms per frame)\n", m.backend.c_str(), m.per_second,
                    pose_ms / frames, m.ms_per_frame - pose_ms / frames);
        std::fflush(stdout);
    }
    const std::string head = "{\"benchmark\":\"crowd\",\"instances\":" + std::to_string(count) + ",\"chains\":" +
                             std::to_string(rods_scene.world.chains.size()) + ",\"frames\":" + std::to_string(frames);
    return report_results(results, "frames/s", head, json_path);
}

// kodawari bench view: what a viewer frame costs (simulate, then draw offscreen and wait;
// no image read back, no blit) with the simulation's state drawn where it is computed
// (the vulkan backends on the renderer's device, issue 5), against the same device with
// the state read back and uploaded again (what a renderer on its own device must do),
// and against the cpu backends (uploaded). The three run interleaved, 10 frames at a time,
// so that a noisy machine slows them alike.
int bench_view(Args& args, BackendChoice choice) {
    const std::uint32_t frames = static_cast<std::uint32_t>(args.count("frames", 1, 100'000).value_or(120));
    const auto [width, height] = image_size(args.option("size"));
    const auto json_path = args.option("json");
    auto positionals = args.positionals();
    if (positionals.size() > 2) throw UsageError{"usage: kodawari bench view [SCENE] [options]"};
    positionals.erase(positionals.begin());
    if (positionals.empty()) positionals.push_back("scenes/crowd.json");
    (void)scene_argument(positionals, "bench view");
    auto loaded = load_scene(positionals[0]);
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
                                               .rod_inputs_on_device = run.source == Simulation::DrawSource::Device});
        if (!made) return report(made.error());
        run.sim = std::move(made).value();
        run.sim->keep_bird_poses(run.source == Simulation::DrawSource::ReadBack);
        if (auto s = run.sim->show_on(*run.renderer); !s) return report(s.error());
    }
    const Simulation& first = *runs.front().sim;
    const std::vector<glm::vec3> grid = render::content_points(first.rod_scene(), nullptr, &first.bird_world());
    std::printf("bench view: scene \"%s\": %zu chains, %zu birds, %ux%u, %u frames per configuration after 2 warm-up frames, "
                "interleaved 10 at a time, on %s\n",
                scene.name.c_str(), first.rod_scene() ? first.rod_scene()->world.chains.size() : std::size_t{0},
                first.bird_world().birds.size(), width, height, frames, runs.front().renderer->device().c_str());
    std::fflush(stdout);

    // One frame of a configuration: simulate, give the renderer the state, draw.
    const auto frame = [&](Run& run) -> Result<void> {
        render::Renderer& r = *run.renderer;
        const std::uint64_t before = r.read_back_bytes();
        KW_TRY(run.sim->step());
        KW_TRY(run.sim->draw_on(r, run.source));
        const std::uint32_t f = *run.sim->frame();
        render::DrawList list(render::scene_camera(scene, f), width, height);
        render::add_ground_grid(list, grid);
        if (run.sim->rod_scene()) render::add_characters(list, *run.sim->rod_scene(), f);
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
    std::string json = "{\"benchmark\":\"view\",\"scene\":\"" + json_escape(scene.name) + "\",\"frames\":" +
                       std::to_string(frames) + ",\"results\":[";
    for (std::size_t i = 0; i < runs.size(); ++i) {
        const Run& run = runs[i];
        const double fps = frames / run.seconds;
        // The cpu backends' state is on the host already: nothing to read back from a device.
        char bytes[32] = "-";
        if (run.kind == BackendKind::Vulkan) std::snprintf(bytes, sizeof bytes, "%.0f", static_cast<double>(run.read_back_bytes) / frames);
        std::printf("%-16s %12.4g %12.3f %22s %17.2fx\n", run.name, fps, 1e3 * run.seconds / frames, bytes, fps / baseline);
        char numbers[200];
        std::snprintf(numbers, sizeof numbers, "\"per_second\":%.6g,\"ms_per_frame\":%.6g,\"read_back_bytes_per_frame\":%.6g", fps,
                      1e3 * run.seconds / frames, static_cast<double>(run.read_back_bytes) / frames);
        json += (i ? "," : "") + std::string("{\"configuration\":\"") + run.name + "\"," + numbers + "}";
    }
    json += "]}\n";
    return json_path ? write_json(*json_path, json) : kExitOk;
}

}  // namespace

int cmd_bench(Args args) {
    BackendChoice choice = read_backend_choice(args);
    if (args.first_word() == "chains") return bench_chains(args, choice);
    if (args.first_word() == "crowd") return bench_crowd(args, choice);
    if (args.first_word() == "view") return bench_view(args, choice);
    const std::uint32_t count = static_cast<std::uint32_t>(args.count("count", 1, 4'000'000).value_or(1'000'000));
    const std::uint32_t frames = static_cast<std::uint32_t>(args.count("frames", 1, 100'000).value_or(30));
    const auto json_path = args.option("json");
    const bool readback = args.flag("readback");
    const auto positionals = args.positionals();
    if (positionals.size() != 1 || positionals[0] != "birds") {
        throw UsageError{"usage: kodawari bench birds|chains|crowd|view [options]"};
    }
    const std::vector<BackendKind> kinds = read_backends(args);

    auto built = build_bird_world(bench_scene(count, frames));
    if (!built) return report(built.error());
    const birds::BirdWorld& world = built.value();
    std::printf("bench birds: %u birds (pigeon, gull, hawk), %u frames at 60 fps after 1 warm-up frame per backend, %s\n", count,
                frames, readback ? "poses read back every frame" : "no readback");
    std::fflush(stdout);

    std::vector<gpu::BirdPose> poses(readback ? std::size_t{count} : 0);
    std::vector<Measured> results;
    for (BackendKind kind : kinds) {
        auto backend = make_bird_backend(kind, choice.options);
        if (!backend) {
            std::printf("  %-14s skipped: %s\n", std::string(backend_name(kind)).c_str(), backend.error().message.c_str());
            continue;
        }
        BirdBackend& b = *backend.value();
        if (auto r = b.load(world); !r) return report(r.error());
        // Warm-up: lavapipe compiles the kernel at its first dispatch.
        if (auto r = b.simulate(1, {poses, {}}); !r) return report(r.error());
        double gpu_ms = 0.0;
        const auto start = std::chrono::steady_clock::now();
        if (readback) {
            for (std::uint32_t f = 0; f < frames; ++f) {
                if (auto r = b.simulate(1, {poses, {}}); !r) return report(r.error());
                gpu_ms += b.last_gpu_ms();
            }
        } else {
            if (auto r = b.simulate(frames, {}); !r) return report(r.error());
            gpu_ms = b.last_gpu_ms();
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        Measured m{std::string(b.name()), b.device(), static_cast<double>(count) * frames / seconds, 1e3 * seconds / frames,
                   b.last_gpu_ms() >= 0.0 ? gpu_ms / frames : -1.0};
        if (validation_failed(b.validation_messages())) return kExitFailure;
        results.push_back(m);
        std::printf("  %-14s done: %.3g bird-frames/s\n", m.backend.c_str(), m.per_second);
        std::fflush(stdout);
    }

    const std::string head = "{\"benchmark\":\"birds\",\"count\":" + std::to_string(count) + ",\"frames\":" +
                             std::to_string(frames) + ",\"readback\":" + (readback ? "true" : "false");
    return report_results(results, "bird-frames/s", head, json_path);
}

}  // namespace kodawari::cli
