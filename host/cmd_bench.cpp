#include <algorithm>
#include <chrono>
#include <functional>
#include <optional>
#include <cstdio>
#include <sstream>
#include <vector>

#include "bench_common.hpp"
#include "commands.hpp"
#include "kodawari/atomic_file.hpp"
#include "kodawari/backend_factory.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/domains/scene_draw.hpp"
#include "kodawari/rod_backend.hpp"
#include "kodawari/scene.hpp"
#include "kodawari/rods/synthetic.hpp"
#include "kodawari/scene.hpp"
#include "kodawari/simd.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/simulation.hpp"

namespace kodawari::cli {

std::string json_escape(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (c == '"' || c == '\\') out += '\\';
        if (static_cast<unsigned char>(c) >= 0x20) out += c;
    }
    return out;
}

// Writes a benchmark's JSON atomically and says so.
int write_json(const std::string& path, const std::string& text) {
    auto file = AtomicFile::open(path);
    if (!file) return report(file.error());
    file.value().write(text);
    if (auto r = file.value().commit(); !r) return report(r.error());
    std::printf("wrote %s\n", path.c_str());
    return kExitOk;
}

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

// One backend's figures: a rate per repetition (bird-frames, joint-steps or frames per
// second) and what it ran on.
struct Measured {
    std::string backend, device;
    std::string isa;       // the cpu backend's SIMD instruction set, "" for the others
    unsigned threads = 0;  // CPU threads of the cpu kinds, 0 for vulkan (lavapipe has its own)
    std::vector<double> per_second, ms_per_frame;
    // The device's timestamps per frame, one value per repetition; empty when the backend
    // has none (the cpu kinds) or a repetition lacked them.
    std::vector<double> gpu_ms_per_frame;
    bool gpu_timed = true;
    std::uint64_t frames = 0;

    [[nodiscard]] static double median(std::vector<double> v) {
        if (v.empty()) return 0.0;
        std::sort(v.begin(), v.end());
        const std::size_t n = v.size();
        return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    }
    [[nodiscard]] double rate() const { return median(per_second); }
    [[nodiscard]] double min() const { return per_second.empty() ? 0.0 : *std::min_element(per_second.begin(), per_second.end()); }
    [[nodiscard]] double max() const { return per_second.empty() ? 0.0 : *std::max_element(per_second.begin(), per_second.end()); }
    /// The median GPU ms per frame, the same statistic as the wall ms/frame beside it;
    /// < 0 when not measured.
    [[nodiscard]] double gpu_ms() const { return gpu_timed && !gpu_ms_per_frame.empty() ? median(gpu_ms_per_frame) : -1.0; }
};

// A backend set up and warmed up, and one timed repetition of it: returns the seconds it
// took and adds the GPU milliseconds it measured (or makes them negative).
struct Contender {
    Measured measured;
    std::function<Result<double>(double& gpu_ms)> repetition;
};


// What every benchmark takes: the backend options, the backends to time, how often, where
// the JSON goes.
struct BenchCommon {
    BackendFlags backend;
    std::optional<std::string> backends;
    std::optional<std::uint64_t> repetitions;
    std::optional<std::string> json;
};

std::vector<BackendKind> read_backends(const BenchCommon& o) {
    // --backend NAME, which every other command takes, times that one backend here.
    if (o.backend.backend && o.backends) throw UsageError{"--backend and --backends exclude each other: give one"};
    if (o.backend.backend && *o.backend.backend == "auto") {
        throw UsageError{"--backend: bench times named backends (cpu-reference, cpu, vulkan), not auto"};
    }
    std::vector<BackendKind> kinds;
    std::stringstream names(o.backend.backend ? *o.backend.backend : o.backends.value_or("cpu-reference,cpu,vulkan"));
    for (std::string name; std::getline(names, name, ',');) {
        auto kind = parse_backend_choice(name);
        if (!kind || !kind.value()) throw UsageError{"--backends: unknown backend \"" + name + "\""};
        kinds.push_back(*kind.value());
    }
    return kinds;
}

// --repetitions: how many timed runs of every backend the medians come from.
std::uint32_t read_repetitions(const BenchCommon& o) { return static_cast<std::uint32_t>(o.repetitions.value_or(3)); }

// The ISA and threads a backend of `kind` runs with (what the table and the JSON say).
void describe(Measured& m, BackendKind kind, const BackendOptions& options) {
    if (kind == BackendKind::Cpu) {
        auto isa = simd_isa(options.isa);
        m.isa = isa ? isa.value() : "";
        m.threads = cpu_backend_threads(options);
    } else if (kind == BackendKind::CpuReference) {
        m.threads = 1;
    }
}

// The repetitions, interleaved (repetition r of every backend, then r + 1) so that a
// noisy machine slows them alike.
Result<void> run_repetitions(std::vector<Contender>& contenders, std::uint32_t repetitions, std::uint64_t frames_per_repetition,
                             double work_per_frame) {
    for (std::uint32_t r = 0; r < repetitions; ++r) {
        for (Contender& c : contenders) {
            double gpu_ms = 0.0;
            auto seconds = c.repetition(gpu_ms);
            if (!seconds) return seconds.error();
            Measured& m = c.measured;
            m.per_second.push_back(work_per_frame * static_cast<double>(frames_per_repetition) / seconds.value());
            m.ms_per_frame.push_back(1e3 * seconds.value() / static_cast<double>(frames_per_repetition));
            if (gpu_ms < 0.0) m.gpu_timed = false;
            m.gpu_ms_per_frame.push_back(gpu_ms / static_cast<double>(frames_per_repetition));
            m.frames += frames_per_repetition;
        }
    }
    for (const Contender& c : contenders) {
        std::printf("  %-14s done: %.4g (min %.4g, max %.4g)\n", c.measured.backend.c_str(), c.measured.rate(), c.measured.min(),
                    c.measured.max());
    }
    std::fflush(stdout);
    return {};
}


// The table and the --json file, the same shape for every benchmark: each backend's median
// rate with its min and max over the repetitions, its ratio to cpu-reference and to cpu
// (medians of the same run), the ISA and the threads.
int report_results(const std::vector<Contender>& contenders, const char* unit, std::uint32_t repetitions,
                   const BackendOptions& options, const std::string& json_head, const std::optional<std::string>& json_path) {
    double reference = 0.0, cpu = 0.0;
    for (const auto& c : contenders) {
        if (c.measured.backend == "cpu-reference") reference = c.measured.rate();
        if (c.measured.backend == "cpu") cpu = c.measured.rate();
    }
    auto ratio = [](double value, double base) {
        char text[32] = "-";
        if (base > 0.0) std::snprintf(text, sizeof text, "%.2fx", value / base);
        return std::string(text);
    };
    auto isa = simd_isa(options.isa);
    const std::string cpu_isa = isa ? isa.value() : "";
    const unsigned cpu_threads = cpu_backend_threads(options);
    std::printf("\nmedians of %u repetitions (min and max beside them), after warm-up; cpu: %s, %u threads\n", repetitions,
                cpu_isa.c_str(), cpu_threads);
    std::printf("%-14s %-36s %14s %11s %11s %10s %12s %9s %7s %-7s %7s\n", "backend", "device", unit, "min", "max", "ms/frame",
                "GPU ms/frame", "vs c-ref", "vs cpu", "isa", "threads");
    bool gpu_above_wall = false;
    for (const auto& c : contenders) {
        const Measured& m = c.measured;
        char gpu[32] = "-";
        if (m.gpu_ms() >= 0.0) std::snprintf(gpu, sizeof gpu, "%.3f", m.gpu_ms());
        if (m.gpu_ms() > Measured::median(m.ms_per_frame)) gpu_above_wall = true;
        std::printf("%-14s %-36s %14.4g %11.4g %11.4g %10.3f %12s %9s %7s %-7s %7s\n", m.backend.c_str(), m.device.c_str(), m.rate(),
                    m.min(), m.max(), Measured::median(m.ms_per_frame), gpu, ratio(m.rate(), reference).c_str(),
                    ratio(m.rate(), cpu).c_str(), m.isa.empty() ? "-" : m.isa.c_str(),
                    m.threads == 0 ? "-" : std::to_string(m.threads).c_str());
    }
    std::printf("(ms/frame: wall time per frame; GPU ms/frame: the device's timestamps around the frame's dispatches, "
                "host preparation and waiting left out, '-' without timestamps; both medians of the repetitions)\n");
    // The timestamps bracket the dispatches alone, so they cannot exceed the wall time of
    // the same frames unless the device's clock disagrees with the host's (lavapipe's
    // timestamps are the CPU's clock, read by its own threads).
    if (gpu_above_wall) std::printf("note: GPU time above wall time: the device's timestamp clock disagrees with the host's\n");
    if (!json_path) return kExitOk;
    std::string text = json_head + ",\"isa\":\"" + json_escape(cpu_isa) + "\",\"threads\":" + std::to_string(cpu_threads) +
                       ",\"repetitions\":" + std::to_string(repetitions) + ",\"results\":[";
    for (std::size_t i = 0; i < contenders.size(); ++i) {
        const Measured& m = contenders[i].measured;
        char numbers[320];
        std::snprintf(numbers, sizeof numbers,
                      "\"per_second\":%.6g,\"min\":%.6g,\"max\":%.6g,\"ms_per_frame\":%.6g,\"gpu_ms_per_frame\":%s,"
                      "\"vs_cpu_reference\":%s,\"vs_cpu\":%s",
                      m.rate(), m.min(), m.max(), Measured::median(m.ms_per_frame),
                      m.gpu_ms() >= 0.0 ? std::to_string(m.gpu_ms()).c_str() : "null",
                      reference > 0.0 ? std::to_string(m.rate() / reference).c_str() : "null",
                      cpu > 0.0 ? std::to_string(m.rate() / cpu).c_str() : "null");
        text += (i ? "," : "") + std::string("{\"backend\":\"") + m.backend + "\",\"device\":\"" + json_escape(m.device) + "\"," +
                numbers + ",\"isa\":" + (m.isa.empty() ? "null" : "\"" + m.isa + "\"") +
                ",\"threads\":" + (m.threads == 0 ? "null" : std::to_string(m.threads)) + "}";
    }
    text += "]}\n";
    return write_json(*json_path, text);
}

// kodawari bench chains: every backend on the same procedural chains (rods/synthetic.hpp),
// one solver substep per step, joint-steps per second = chains x joints x steps / s.
struct ChainsOptions {
    BenchCommon common;
    std::optional<std::uint64_t> count;
    std::optional<std::uint64_t> chains;  // the old spelling of --count
    std::optional<std::uint64_t> joints;
    std::optional<std::uint64_t> iterations;
    std::optional<std::uint64_t> frames;
    std::optional<std::uint64_t> steps;  // the old spelling of --frames
};

int bench_chains(ChainsOptions o) {
    // --chains and --steps were this benchmark's own names for what every other command
    // calls --count and --frames (and rig's --chains is something else).
    take_alias(o.count, o.chains, "bench chains --chains", "--count");
    take_alias(o.frames, o.steps, "bench chains --steps", "--frames");
    const BackendChoice choice = read_backend_choice(o.common.backend);
    rods::SyntheticOptions options;
    options.chains = static_cast<std::uint32_t>(o.count.value_or(100'000));
    options.joints = static_cast<std::uint32_t>(o.joints.value_or(16));
    options.iterations = static_cast<std::uint32_t>(o.iterations.value_or(4));
    const std::uint32_t steps = static_cast<std::uint32_t>(o.frames.value_or(10));
    const std::uint32_t repetitions = read_repetitions(o.common);
    const auto& json_path = o.common.json;
    const std::vector<BackendKind> kinds = read_backends(o.common);
    auto made = rods::SyntheticScene::make(options);
    if (!made) return report(made.error());
    const rods::SyntheticScene& scene = made.value();
    const float dt = rods::SolverParams{}.max_substep;  // one substep per step
    std::printf("bench chains: %u chains x %u joints, %u iterations, %u view examples, a head collider each; %u repetitions "
                "of %u steps of 1/120 s per backend, interleaved, after 1 warm-up step each (it also compiles the kernel)\n",
                options.chains, options.joints, options.iterations, options.views, repetitions, steps);
    std::fflush(stdout);
    // The kinematic input of every step, made before timing: it is the caller's work.
    std::vector<rods::RodFrame> frames(std::size_t{steps} * repetitions + 2);
    for (std::uint32_t f = 0; f < frames.size(); ++f) scene.frame(f, dt, frames[f]);

    std::vector<std::unique_ptr<RodBackend>> backends;
    std::vector<std::size_t> next;  // per contender: the next frame to step
    std::vector<Contender> contenders;
    for (BackendKind kind : kinds) {
        auto backend = make_rod_backend(kind, choice.options);
        if (!backend) {
            std::printf("  %-14s skipped: %s\n", std::string(backend_name(kind)).c_str(), backend.error().message.c_str());
            continue;
        }
        RodBackend& b = *backend.value();
        if (auto r = b.load(scene.world(), frames[0]); !r) return report(r.error());
        if (auto r = b.step(frames[1]); !r) return report(r.error());
        const std::size_t index = backends.size();
        backends.push_back(std::move(backend).value());
        next.push_back(2);
        Contender c;
        c.measured.backend = std::string(b.name());
        c.measured.device = b.device();
        describe(c.measured, kind, choice.options);
        c.repetition = [&, index, steps](double& gpu_ms) -> Result<double> {
            RodBackend& rb = *backends[index];
            const auto start = std::chrono::steady_clock::now();
            for (std::uint32_t f = 0; f < steps; ++f) {
                KW_TRY(rb.step(frames[next[index]++]));
                gpu_ms = rb.last_gpu_ms() < 0.0 || gpu_ms < 0.0 ? -1.0 : gpu_ms + rb.last_gpu_ms();
            }
            return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        };
        contenders.push_back(std::move(c));
    }
    if (auto r = run_repetitions(contenders, repetitions, steps, static_cast<double>(options.chains) * options.joints); !r) {
        return report(r.error());
    }
    for (const auto& b : backends) {
        if (validation_failed(b->validation_messages())) return kExitFailure;
    }
    const std::string head = "{\"benchmark\":\"chains\",\"chains\":" + std::to_string(options.chains) +
                             ",\"joints\":" + std::to_string(options.joints) + ",\"iterations\":" +
                             std::to_string(options.iterations) + ",\"steps\":" + std::to_string(steps);
    return report_results(contenders, "joint-steps/s", repetitions, choice.options, head, json_path);
}


// kodawari bench crowd: every backend on the same crowd of skinned (rigged glTF)
// characters: per frame the clips of every instance (the pose backend of that kind) and
// the chains' step (the rod backend of that kind). Frames per second of the two together.
struct CrowdOptions {
    BenchCommon common;
    std::optional<std::string> scene;
    std::optional<std::uint64_t> count;
    std::optional<std::uint64_t> frames;
};

int bench_crowd(const CrowdOptions& o) {
    const BackendChoice choice = read_backend_choice(o.common.backend);
    const std::uint32_t count = static_cast<std::uint32_t>(o.count.value_or(1000));
    const std::uint32_t frames = static_cast<std::uint32_t>(o.frames.value_or(60));
    const std::uint32_t repetitions = read_repetitions(o.common);
    const auto& json_path = o.common.json;
    const std::vector<BackendKind> kinds = read_backends(o.common);
    const std::string path = o.scene.value_or("scenes/crowd-gltf.json");
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
    std::printf("bench crowd: %u instances of %s (%zu nodes, %zu clips), %zu chains, %u joints; %u repetitions of %u frames at "
                "%g fps per backend, interleaved, after 2 warm-up frames each (they also compile the kernels)\n",
                count, character.source.c_str(), character.nodes.size(), character.animations.size(),
                rods_scene.world.chains.size(), rods_scene.world.joint_count, repetitions, frames,
                static_cast<double>(rods_scene.fps));
    std::fflush(stdout);

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
    std::vector<std::unique_ptr<Simulation>> sims;
    std::vector<Contender> contenders;
    std::vector<double> clip_ms(variants.size(), 0.0);  // per contender, summed over its timed frames
    for (const auto [kind, device_input] : variants) {
        // Frame 0 (load) and 2 warm-up steps, then the timed frames.
        auto made = Simulation::create(scene, {.backend = kind, .options = choice.options, .frames = frames * repetitions + 3,
                                               .device_inputs = device_input});
        if (!made) {
            std::printf("  %-14s skipped: %s\n", std::string(backend_name(kind)).c_str(), made.error().message.c_str());
            continue;
        }
        Simulation& sim = *made.value();
        if (auto r = sim.step(3); !r) return report(r.error());
        if (device_input && !rod_inputs_on_device(sim)) {
            return report(make_error(Error::Kind::Internal, "the rod input could not go on the device"));
        }
        const std::size_t index = sims.size();
        sims.push_back(std::move(made).value());
        Contender c;
        c.measured.backend =
            std::string(backend_name(kind)) + (kind == BackendKind::Vulkan ? (device_input ? "/dev-in" : "/host-in") : "");
        c.measured.device = sim.device();
        describe(c.measured, kind, choice.options);
        c.repetition = [&, index, frames](double& gpu_ms) -> Result<double> {
            Simulation& s = *sims[index];
            const ChainTiming before = chain_timing(s);
            const auto start = std::chrono::steady_clock::now();
            for (std::uint32_t f = 0; f < frames; ++f) KW_TRY(s.step());
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            const double chain_gpu = chain_timing(s).gpu_ms - before.gpu_ms;
            gpu_ms = chain_gpu > 0.0 ? chain_gpu : -1.0;
            clip_ms[index] += chain_timing(s).pose_ms - before.pose_ms;
            return seconds;
        };
        contenders.push_back(std::move(c));
    }
    if (auto r = run_repetitions(contenders, repetitions, frames, 1.0); !r) return report(r.error());
    // Where a frame's time goes (means over every timed frame): the clips (the pose backend,
    // and for host-in the matrices read back and the rod input made from them) and the rest.
    for (std::size_t i = 0; i < contenders.size(); ++i) {
        const Measured& m = contenders[i].measured;
        double total_ms = 0.0;
        for (const double ms : m.ms_per_frame) total_ms += ms * frames;
        const double clips = clip_ms[i] / static_cast<double>(m.frames);
        std::printf("  %-14s clips %.3f ms + chains %.3f ms per frame (means)\n", m.backend.c_str(), clips,
                    total_ms / static_cast<double>(m.frames) - clips);
    }
    for (const auto& s : sims) {
        if (validation_failed(s->validation_messages())) return kExitFailure;
    }
    const std::string head = "{\"benchmark\":\"crowd\",\"instances\":" + std::to_string(count) + ",\"chains\":" +
                             std::to_string(rods_scene.world.chains.size()) + ",\"frames\":" + std::to_string(frames);
    return report_results(contenders, "frames/s", repetitions, choice.options, head, json_path);
}


struct BirdsOptions {
    BenchCommon common;
    std::optional<std::uint64_t> count;
    std::optional<std::uint64_t> frames;
    bool readback = false;
};

int bench_birds(const BirdsOptions& o) {
    const BackendChoice choice = read_backend_choice(o.common.backend);
    const std::uint32_t count = static_cast<std::uint32_t>(o.count.value_or(1'000'000));
    const std::uint32_t frames = static_cast<std::uint32_t>(o.frames.value_or(30));
    const std::uint32_t repetitions = read_repetitions(o.common);
    const auto& json_path = o.common.json;
    const bool readback = o.readback;
    const std::vector<BackendKind> kinds = read_backends(o.common);

    auto built = build_bird_world(bench_scene(count, frames * repetitions + 1));
    if (!built) return report(built.error());
    const birds::BirdWorld& world = built.value();
    std::printf("bench birds: %u birds (pigeon, gull, hawk), %u repetitions of %u frames at 60 fps per backend, interleaved, "
                "after 1 warm-up frame each, %s\n",
                count, repetitions, frames, readback ? "poses read back every frame" : "no readback");
    std::fflush(stdout);

    std::vector<gpu::BirdPose> poses(readback ? std::size_t{count} : 0);
    std::vector<std::unique_ptr<BirdBackend>> backends;
    std::vector<Contender> contenders;
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
        const std::size_t index = backends.size();
        backends.push_back(std::move(backend).value());
        Contender c;
        c.measured.backend = std::string(b.name());
        c.measured.device = b.device();
        describe(c.measured, kind, choice.options);
        c.repetition = [&, index, frames, readback](double& gpu_ms) -> Result<double> {
            BirdBackend& bb = *backends[index];
            const auto start = std::chrono::steady_clock::now();
            if (readback) {
                for (std::uint32_t f = 0; f < frames; ++f) {
                    KW_TRY(bb.simulate(1, {poses, {}}));
                    gpu_ms = bb.last_gpu_ms() < 0.0 || gpu_ms < 0.0 ? -1.0 : gpu_ms + bb.last_gpu_ms();
                }
            } else {
                KW_TRY(bb.simulate(frames, {}));
                gpu_ms = bb.last_gpu_ms();
            }
            return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        };
        contenders.push_back(std::move(c));
    }
    if (auto r = run_repetitions(contenders, repetitions, frames, static_cast<double>(count)); !r) return report(r.error());
    for (const auto& b : backends) {
        if (validation_failed(b->validation_messages())) return kExitFailure;
    }
    const std::string head = "{\"benchmark\":\"birds\",\"count\":" + std::to_string(count) + ",\"frames\":" +
                             std::to_string(frames) + ",\"readback\":" + (readback ? "true" : "false");
    return report_results(contenders, "bird-frames/s", repetitions, choice.options, head, json_path);
}

void add_common(CLI::App& c, BenchCommon& o) {
    add_text(c, "--backends", o.backends, "LIST", "the backends to time, comma-separated (default: cpu-reference,cpu,vulkan)");
    add_count(c, "--repetitions", o.repetitions, 3, 1000, "timed runs of every backend, interleaved (default: 3)");
    add_text(c, "--json", o.json, "FILE.json", "also write the results as JSON (default: none)");
    add_backend_options(c, o.backend);
    c.get_option("--backend")->description("time this one backend, as --backends NAME (default: the --backends list)");
}

}  // namespace

Command add_bench(CLI::App& app) {
    CLI::App* bench = app.add_subcommand("bench", "time every backend on the same work after warm-up: medians, min, max and the "
                                                  "ratios to cpu-reference and cpu (docs/performance.md)");
    bench->require_subcommand(1);
    bench->footer("Columns: the rate (median of the repetitions) with min and max; ms/frame, wall time per frame; GPU "
                  "ms/frame, the device's timestamps around the frame's dispatches (host preparation and waiting left out; "
                  "'-' for the cpu kinds); both medians of the repetitions; vs c-ref and vs cpu, the rate over "
                  "cpu-reference's and cpu's of the same run; isa and threads of the cpu backends. --json writes the same "
                  "(per_second, min, max, ms_per_frame, gpu_ms_per_frame, vs_cpu_reference, vs_cpu, isa, threads); "
                  "docs/performance.md.");
    auto birds = std::make_shared<BirdsOptions>();
    CLI::App* b = bench->add_subcommand("birds", "bird-frames per second on a flock of N birds");
    add_count(*b, "--count", birds->count, 1, 4'000'000, "birds (default: 1000000)");
    add_count(*b, "--frames", birds->frames, 1, 100'000, "frames per repetition (default: 30)");
    add_switch(*b, "--readback", birds->readback, "read the poses back every frame (default: off)");
    add_common(*b, birds->common);

    auto chains = std::make_shared<ChainsOptions>();
    CLI::App* ch = bench->add_subcommand("chains", "joint-steps per second on procedural chains, one solver substep per frame");
    add_count(*ch, "--count", chains->count, 1, 2'000'000, "chains (default: 100000)");
    add_count(*ch, "--chains", chains->chains, 1, 2'000'000, "deprecated: the old spelling of --count, for one release");
    add_count(*ch, "--joints", chains->joints, 2, rods::kMaxChainJoints, "joints per chain (default: 16)");
    add_count(*ch, "--iterations", chains->iterations, 1, 64, "solver iterations per substep (default: 4)");
    add_count(*ch, "--frames", chains->frames, 1, 100'000, "frames (steps of 1/120 s) per repetition (default: 10)");
    add_count(*ch, "--steps", chains->steps, 1, 100'000, "deprecated: the old spelling of --frames, for one release");
    add_common(*ch, chains->common);

    auto crowd = std::make_shared<CrowdOptions>();
    CLI::App* cr = bench->add_subcommand("crowd", "frames per second of a crowd of N skinned characters: clips and chains");
    add_scene(*cr, crowd->scene, "scenes/crowd-gltf.json");
    add_count(*cr, "--count", crowd->count, 1, 100'000, "characters (default: 1000)");
    add_count(*cr, "--frames", crowd->frames, 1, 100'000, "frames per repetition (default: 60)");
    add_common(*cr, crowd->common);

    std::function<int()> run_view;
    add_bench_view(*bench, run_view);

    return {bench, [=] {
                if (b->parsed()) return bench_birds(*birds);
                if (ch->parsed()) return bench_chains(*chains);
                if (cr->parsed()) return bench_crowd(*crowd);
                return run_view();
            }};
}

}  // namespace kodawari::cli
