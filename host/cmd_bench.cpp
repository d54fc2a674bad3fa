#include <algorithm>
#include <chrono>
#include <optional>
#include <cstdio>
#include <sstream>
#include <vector>

#include "commands.hpp"
#include "kodawari/atomic_file.hpp"
#include "kodawari/crowd_animator.hpp"
#include "kodawari/rod_backend.hpp"
#include "kodawari/rod_scene.hpp"
#include "kodawari/rods/synthetic.hpp"
#include "kodawari/scene.hpp"

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
        auto kind = parse_backend(name);
        if (!kind) throw UsageError{"--backends: unknown backend \"" + name + "\""};
        kinds.push_back(*kind);
    }
    return kinds;
}

// The table and the --json file, the same shape for every benchmark.
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
        auto file = AtomicFile::open(*json_path);
        if (!file) return report(file.error());
        file.value().write(text);
        if (auto r = file.value().commit(); !r) return report(r.error());
        std::printf("wrote %s\n", json_path->c_str());
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
        if (b.validation_messages() > 0) {
            std::fprintf(stderr, "kodawari: error: Vulkan validation reported %u messages\n", b.validation_messages());
            return kExitFailure;
        }
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
    rods::RodFrame input;
    for (BackendKind kind : kinds) {
        auto backend = make_rod_backend(kind, choice.options);
        if (!backend) {
            std::printf("  %-14s skipped: %s\n", std::string(backend_name(kind)).c_str(), backend.error().message.c_str());
            continue;
        }
        auto animator = CrowdAnimator::create(rods_scene, kind, choice.options);
        if (!animator) return report(animator.error());
        RodBackend& b = *backend.value();
        if (auto r = animator.value().frame(0, input); !r) return report(r.error());
        if (auto r = b.load(rods_scene.world, input); !r) return report(r.error());
        for (std::uint32_t f = 1; f <= 2; ++f) {
            if (auto r = animator.value().frame(f, input); !r) return report(r.error());
            if (auto r = b.step(input); !r) return report(r.error());
        }
        double pose_ms = 0.0, gpu_ms = 0.0;
        const auto start = std::chrono::steady_clock::now();
        for (std::uint32_t f = 3; f < frames + 3; ++f) {
            if (auto r = animator.value().frame(f, input); !r) return report(r.error());
            pose_ms += animator.value().last_pose_ms();
            if (auto r = b.step(input); !r) return report(r.error());
            gpu_ms += b.last_gpu_ms();
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (b.validation_messages() + animator.value().validation_messages() > 0) {
            std::fprintf(stderr, "kodawari: error: Vulkan validation reported %u messages\n",
                         b.validation_messages() + animator.value().validation_messages());
            return kExitFailure;
        }
        Measured m{std::string(b.name()), b.device(), frames / seconds, 1e3 * seconds / frames,
                   b.last_gpu_ms() >= 0.0 ? gpu_ms / frames : -1.0};
        results.push_back(m);
        std::printf("  %-14s done: %.3g frames/s (clips %.3f ms + chains %.3f ms per frame)\n", m.backend.c_str(), m.per_second,
                    pose_ms / frames, m.ms_per_frame - pose_ms / frames);
        std::fflush(stdout);
    }
    const std::string head = "{\"benchmark\":\"crowd\",\"instances\":" + std::to_string(count) + ",\"chains\":" +
                             std::to_string(rods_scene.world.chains.size()) + ",\"frames\":" + std::to_string(frames);
    return report_results(results, "frames/s", head, json_path);
}

}  // namespace

int cmd_bench(Args args) {
    BackendChoice choice = read_backend_choice(args);
    if (args.first_word() == "chains") return bench_chains(args, choice);
    if (args.first_word() == "crowd") return bench_crowd(args, choice);
    const std::uint32_t count = static_cast<std::uint32_t>(args.count("count", 1, 4'000'000).value_or(1'000'000));
    const std::uint32_t frames = static_cast<std::uint32_t>(args.count("frames", 1, 100'000).value_or(30));
    const auto json_path = args.option("json");
    const bool readback = args.flag("readback");
    const auto positionals = args.positionals();
    if (positionals.size() != 1 || positionals[0] != "birds") {
        throw UsageError{"usage: kodawari bench birds|chains|crowd [options]"};
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
        if (b.validation_messages() > 0) {
            std::fprintf(stderr, "kodawari: error: Vulkan validation reported %u messages\n", b.validation_messages());
            return kExitFailure;
        }
        results.push_back(m);
        std::printf("  %-14s done: %.3g bird-frames/s\n", m.backend.c_str(), m.per_second);
        std::fflush(stdout);
    }

    const std::string head = "{\"benchmark\":\"birds\",\"count\":" + std::to_string(count) + ",\"frames\":" +
                             std::to_string(frames) + ",\"readback\":" + (readback ? "true" : "false");
    return report_results(results, "bird-frames/s", head, json_path);
}

}  // namespace kodawari::cli
