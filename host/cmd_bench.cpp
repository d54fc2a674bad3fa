#include <algorithm>
#include <array>
#include <chrono>
#include <functional>
#include <optional>
#include <cstdio>
#include <sstream>
#include <vector>

#include "bench_common.hpp"
#include "commands.hpp"
#include "kodawari/core/atomic_file.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/domains/scene_draw.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/rods/synthetic.hpp"
#include "kodawari/backends/simd.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/simulation/simulation.hpp"

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
    std::optional<std::string> rod_kernels;
};

// Each vulkan variant once per item of the comma-separated `list` (each one of `names`),
// side by side as "<label>/<item>", `apply` setting the item's option; the others as they
// are. `option` names the flag in errors.
template <typename T, std::size_t N>
std::vector<BenchVariant> per_vulkan_item(std::vector<BenchVariant> variants, const char* option, const std::string& list,
                                          const std::pair<const char*, T> (&names)[N], void (*apply)(BackendOptions&, T)) {
    std::string all;
    for (const auto& n : names) all += (all.empty() ? "" : ", ") + std::string(n.first);
    std::vector<std::pair<std::string, T>> chosen;
    std::stringstream items(list);
    for (std::string item; std::getline(items, item, ',');) {
        const auto* found = std::find_if(std::begin(names), std::end(names), [&](const auto& n) { return item == n.first; });
        if (found == std::end(names)) throw UsageError{std::string(option) + ": \"" + item + "\" is none of " + all};
        // An item named twice is timed once, as in --backends and --workgroup-sizes.
        const bool seen = std::any_of(chosen.begin(), chosen.end(), [&](const auto& c) { return c.first == item; });
        if (!seen) chosen.emplace_back(found->first, found->second);
    }
    if (chosen.empty()) throw UsageError{std::string(option) + ": expected one or more of " + all};
    if (std::none_of(variants.begin(), variants.end(), [](const BenchVariant& v) { return v.kind == BackendKind::Vulkan; })) {
        warn_ignored(option, "vulkan");
    }
    std::vector<BenchVariant> out;
    for (const BenchVariant& v : variants) {
        if (v.kind != BackendKind::Vulkan) {
            out.push_back(v);
            continue;
        }
        for (const auto& [name, value] : chosen) {
            BenchVariant each = v;
            apply(each.options, value);
            each.label += "/" + name;
            out.push_back(std::move(each));
        }
    }
    return out;
}

// --rod-kernels per-chain,shared-constants,per-joint: each vulkan variant once per rod
// kernel (BackendOptions::rod_kernel).
std::vector<BenchVariant> with_rod_kernels(std::vector<BenchVariant> variants, const std::optional<std::string>& kernels) {
    if (!kernels) return variants;
    constexpr std::pair<const char*, RodKernel> kNames[] = {
        {"per-chain", RodKernel::PerChain}, {"shared-constants", RodKernel::PerChainSharedConstants}, {"per-joint", RodKernel::PerJoint}};
    return per_vulkan_item(std::move(variants), "--rod-kernels", *kernels, kNames,
                           +[](BackendOptions& o, RodKernel k) { o.rod_kernel = k; });
}

int bench_chains(ChainsOptions o) {
    // --chains and --steps were this benchmark's own names for what every other command
    // calls --count and --frames (and rig's --chains is something else).
    take_alias(o.count, o.chains, "bench chains --chains", "--count");
    take_alias(o.frames, o.steps, "bench chains --steps", "--frames");
    const BackendChoice choice = read_backend_choice(o.common.backend);
    check_json_path(o.common.json);
    rods::SyntheticOptions options;
    options.chains = static_cast<std::uint32_t>(o.count.value_or(100'000));
    options.joints = static_cast<std::uint32_t>(o.joints.value_or(16));
    options.iterations = static_cast<std::uint32_t>(o.iterations.value_or(4));
    // The step is timed, not the load: settling every chain at load (rods::settle, 60 or
    // more substeps a chain) took 65 s for 100 000 chains on cpu-reference's one thread
    // and would take minutes for a million, longer than the timed steps themselves.
    options.settle = false;
    const std::uint32_t steps = static_cast<std::uint32_t>(o.frames.value_or(10));
    const std::uint32_t repetitions = read_repetitions(o.common);
    const auto& json_path = o.common.json;
    const std::vector<BenchVariant> variants = with_rod_kernels(read_variants(o.common, choice), o.rod_kernels);
    auto made = rods::SyntheticScene::make(options);
    if (!made) return report(made.error());
    const rods::SyntheticScene& scene = made.value();
    const float dt = rods::SolverParams{}.max_substep;  // one substep per step
    std::printf("bench chains: %u chains x %u joints, %u iterations, %u view examples, a head collider each, starting unsettled; %u "
                "repetitions of %u steps of 1/120 s per backend, interleaved, after 1 warm-up step each (it also compiles the "
                "kernel)\n",
                options.chains, options.joints, options.iterations, options.views, repetitions, steps);
    std::fflush(stdout);
    // The kinematic input of every step, made before timing: it is the caller's work.
    std::vector<rods::RodFrame> frames(std::size_t{steps} * repetitions + 2);
    for (std::uint32_t f = 0; f < frames.size(); ++f) scene.frame(f, dt, frames[f]);

    std::vector<std::unique_ptr<RodBackend>> backends;
    std::vector<std::size_t> next;  // per contender: the next frame to step
    std::vector<Contender> contenders;
    std::vector<Skipped> skipped;
    for (const auto& [kind, backend_options, label] : variants) {
        auto backend = make_rod_backend(kind, backend_options);
        if (!backend) {
            skip(skipped, label, backend.error().message);
            continue;
        }
        RodBackend& b = *backend.value();
        if (auto r = b.load(scene.world(), frames[0]); !r) {
            // A variant this device cannot run (--rod-kernels per-joint at a workgroup size
            // past its shared memory) leaves the others to time.
            if (r.error().kind != Error::Kind::Unsupported) return report(r.error());
            skip(skipped, label, r.error().message);
            continue;
        }
        if (auto r = b.step(frames[1]); !r) return report(r.error());
        const std::size_t index = backends.size();
        backends.push_back(std::move(backend).value());
        next.push_back(2);
        Contender c;
        c.measured.backend = label;
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
                             std::to_string(options.iterations) + ",\"steps\":" + std::to_string(steps) +
                             json_size(options.chains, steps);
    return report_results(contenders, skipped, "joint-steps/s", repetitions, choice.options, head, json_path);
}


// kodawari bench crowd: every backend on the same crowd of skinned (rigged glTF)
// characters: per frame the clips of every instance (the pose backend of that kind) and
// the chains' step (the rod backend of that kind). Frames per second of the two together.
struct CrowdOptions {
    BenchCommon common;
    std::optional<std::string> scene;
    std::optional<std::uint64_t> count;
    std::optional<std::uint64_t> frames;
    LodFlags lod;
};

int bench_crowd(const CrowdOptions& o) {
    const BackendChoice choice = read_backend_choice(o.common.backend);
    check_json_path(o.common.json);
    const std::uint32_t count = static_cast<std::uint32_t>(o.count.value_or(1000));
    const std::uint32_t frames = static_cast<std::uint32_t>(o.frames.value_or(60));
    const std::uint32_t repetitions = read_repetitions(o.common);
    const auto& json_path = o.common.json;
    const std::vector<BenchVariant> backends = read_variants(o.common, choice);
    const std::string path = o.scene ? *o.scene : shipped_scene("scenes/crowd-gltf.json");
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
    apply_lod(o.lod, scene);
    // The scene as each backend's Simulation builds it, for the header line.
    auto built = build_rod_scene(scene);
    if (!built) return report(built.error());
    const RodScene& rods_scene = built.value();
    const animation::Character& character = *rods_scene.characters[crowd.character].rig;
    std::printf("bench crowd: %u instances of %s (%zu nodes, %zu clips), %zu chains, %u joints; %u repetitions of %u frames at "
                "%g fps per backend, interleaved, after 2 warm-up frames each (they also compile the kernels)\n",
                count, character.source.c_str(), character.nodes.size(), character.animations.size(),
                rods_scene.world.chains.size(), rods_scene.world.joint_count, repetitions, frames,
                static_cast<double>(rods_scene.fps));
    std::fflush(stdout);

    // Vulkan twice: the pose matrices read back and the rod input made on the host, then
    // (one device for both backends) the rod input written on the device.
    struct Variant {
        const BenchVariant* backend;
        bool device_input;
    };
    std::vector<Variant> variants;
    for (const BenchVariant& v : backends) {
        variants.push_back({&v, false});
        // A budget ranks the characters by their reference joints on the host (their rod
        // input stays there: set_lod_budget()).
        if (v.kind == BackendKind::Vulkan && !o.lod.budget_ms) variants.push_back({&v, true});
    }
    if (o.lod.budget_ms) {
        std::printf("  a budget of %g ms a frame (clips and chains, measured): vulkan/dev-in left out, the budget keeps the "
                    "rod input on the host\n", static_cast<double>(scene.lod.budget_ms));
    }
    std::vector<std::unique_ptr<Simulation>> sims;
    std::vector<Contender> contenders;
    std::vector<Skipped> skipped;
    std::vector<double> clip_ms(variants.size(), 0.0);  // per contender, summed over its timed frames
    // With levels of detail, the chains at each level (full, posed, hidden, reduced: by
    // rods::Level) summed over every tenth timed frame, per contender.
    const bool lod_on = scene.lod.enabled;
    constexpr std::uint32_t kLevelSampling = 10;
    std::vector<std::array<std::uint64_t, 4>> level_counts(variants.size(), std::array<std::uint64_t, 4>{});
    // And of those chains, the ones that kept their state instead of stepping (the posed and
    // hidden levels' rate, docs/level-of-detail.md "The rate").
    std::vector<std::uint64_t> kept_counts(variants.size(), 0);
    std::vector<rods::Level> levels;
    std::vector<std::uint8_t> kept;
    for (const auto [variant, device_input] : variants) {
        const BackendKind kind = variant->kind;
        // Frame 0 (load) and 2 warm-up steps, then the timed frames.
        auto made = Simulation::create(scene, {.backend = kind, .options = variant->options, .frames = frames * repetitions + 3,
                                               .device_inputs = device_input});
        if (!made) {
            const std::string label =
                variant->label + (kind == BackendKind::Vulkan ? (device_input ? "/dev-in" : "/host-in") : "");
            skip(skipped, label, made.error().message);
            continue;
        }
        Simulation& sim = *made.value();
        if (auto r = apply_measured_budget(o.lod, sim); !r) return report(r.error());
        if (auto r = sim.step(3); !r) return report(r.error());
        if (device_input && !rod_inputs_on_device(sim)) {
            return report(make_error(Error::Kind::Internal, "the rod input could not go on the device"));
        }
        const std::size_t index = sims.size();
        sims.push_back(std::move(made).value());
        Contender c;
        c.measured.backend = variant->label + (kind == BackendKind::Vulkan ? (device_input ? "/dev-in" : "/host-in") : "");
        c.measured.device = sim.device();
        describe(c.measured, kind, choice.options);
        c.repetition = [&, index, frames](double& gpu_ms) -> Result<double> {
            Simulation& s = *sims[index];
            const ChainTiming before = chain_timing(s);
            double seconds = 0.0;
            auto start = std::chrono::steady_clock::now();
            for (std::uint32_t f = 0; f < frames; ++f) {
                KW_TRY(s.step());
                if (!lod_on || f % kLevelSampling != 0) continue;
                // Every tenth frame's levels, read back with the clock stopped.
                seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
                KW_TRY(read_chain_levels(s, levels, &kept));
                for (const rods::Level l : levels) ++level_counts[index][std::min<std::size_t>(static_cast<std::size_t>(l), 3)];
                for (const std::uint8_t k : kept) kept_counts[index] += k;
                start = std::chrono::steady_clock::now();
            }
            seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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
        const double chains = total_ms / static_cast<double>(m.frames) - clips;
        std::printf("  %-20s clips %.3f ms + chains %.3f ms per frame (means)", m.backend.c_str(), clips, chains);
        // The same in the JSON: clip_ms, chain_ms and with levels of detail the shares
        // (fractions of the sampled chains; null without).
        char extra[256];
        std::snprintf(extra, sizeof extra, ",\"clip_ms\":%.6g,\"chain_ms\":%.6g", clips, chains);
        contenders[i].measured.extra_json = extra;
        const auto& n = level_counts[i];
        const auto sampled = static_cast<double>(n[0] + n[1] + n[2] + n[3]);
        if (sampled > 0.0) {
            auto share = [&](std::size_t l) { return static_cast<double>(n[l]) / sampled; };
            const double kept_share = static_cast<double>(kept_counts[i]) / sampled;
            std::printf("; chains full %.1f%%, ", 100.0 * share(0));
            if (scene.lod.reduced_pixels > 0.0f) std::printf("reduced %.1f%%, ", 100.0 * share(3));
            std::printf("posed %.1f%%, hidden %.1f%%, kept their state %.1f%% (every %uth frame)", 100.0 * share(1),
                        100.0 * share(2), 100.0 * kept_share, kLevelSampling);
            std::snprintf(extra, sizeof extra,
                          ",\"full_share\":%.6g,\"reduced_share\":%.6g,\"posed_share\":%.6g,\"hidden_share\":%.6g,\"kept_share\":%.6g",
                          share(0), share(3), share(1), share(2), kept_share);
        } else {
            std::snprintf(extra, sizeof extra,
                          ",\"full_share\":null,\"reduced_share\":null,\"posed_share\":null,\"hidden_share\":null,\"kept_share\":null");
        }
        contenders[i].measured.extra_json += extra;
        std::printf("\n");
    }
    for (const auto& s : sims) {
        if (validation_failed(s->validation_messages())) return kExitFailure;
    }
    const std::string head = "{\"benchmark\":\"crowd\",\"instances\":" + std::to_string(count) + ",\"chains\":" +
                             std::to_string(rods_scene.world.chains.size()) + json_size(count, frames);
    return report_results(contenders, skipped, "frames/s", repetitions, choice.options, head, json_path);
}


struct BirdsOptions {
    BenchCommon common;
    std::optional<std::uint64_t> count;
    std::optional<std::uint64_t> frames;
    bool readback = false;
    std::optional<std::string> pose_layouts;
};

// --pose-layouts records,fields: each vulkan variant once per layout of its poses
// (BackendOptions::bird_pose_fields).
std::vector<BenchVariant> with_pose_layouts(std::vector<BenchVariant> variants, const BirdsOptions& o) {
    if (!o.pose_layouts) return variants;
    if (o.readback) throw UsageError{"--pose-layouts and --readback exclude each other: poses laid out as fields are not read back"};
    constexpr std::pair<const char*, bool> kNames[] = {{"records", false}, {"fields", true}};
    return per_vulkan_item(std::move(variants), "--pose-layouts", *o.pose_layouts, kNames,
                           +[](BackendOptions& options, bool fields) { options.bird_pose_fields = fields; });
}

int bench_birds(const BirdsOptions& o) {
    const BackendChoice choice = read_backend_choice(o.common.backend);
    check_json_path(o.common.json);
    const std::uint32_t count = static_cast<std::uint32_t>(o.count.value_or(1'000'000));
    const std::uint32_t frames = static_cast<std::uint32_t>(o.frames.value_or(30));
    const std::uint32_t repetitions = read_repetitions(o.common);
    const std::vector<BenchVariant> variants = with_pose_layouts(read_variants(o.common, choice), o);
    const auto& json_path = o.common.json;
    const bool readback = o.readback;

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
    std::vector<Skipped> skipped;
    for (const auto& [kind, backend_options, label] : variants) {
        auto backend = make_bird_backend(kind, backend_options);
        if (!backend) {
            skip(skipped, label, backend.error().message);
            continue;
        }
        BirdBackend& b = *backend.value();
        if (auto r = b.load(world); !r) {
            // A backend that cannot run this size (more birds than one dispatch of the
            // device covers) leaves the others to time.
            if (r.error().kind != Error::Kind::Unsupported) return report(r.error());
            skip(skipped, label, r.error().message);
            continue;
        }
        // Warm-up: lavapipe compiles the kernel at its first dispatch.
        if (auto r = b.simulate(1, {poses, {}}); !r) return report(r.error());
        const std::size_t index = backends.size();
        backends.push_back(std::move(backend).value());
        Contender c;
        c.measured.backend = label;
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
    const std::string head = "{\"benchmark\":\"birds\"" + json_size(count, frames) + ",\"readback\":" + (readback ? "true" : "false");
    return report_results(contenders, skipped, "bird-frames/s", repetitions, choice.options, head, json_path);
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
                  "(per_second, min, max, ms_per_frame, gpu_ms_per_frame, vs_cpu_reference, vs_cpu, isa, threads; bench "
                  "crowd also clip_ms, chain_ms and the levels' full_share, reduced_share, posed_share, hidden_share, kept_share); "
                  "the size as count and frames in every benchmark (chains also its older chains and steps, crowd instances); "
                  "skipped, each backend not timed with why (a row of the table too; nothing timed at all exits 1); "
                  "docs/performance.md.");
    auto birds = std::make_shared<BirdsOptions>();
    CLI::App* b = bench->add_subcommand("birds", "bird-frames per second on a flock of N birds");
    add_count(*b, "--count", birds->count, 1, 20'000'000, "birds, 1 to 20000000 (default: 1000000)");
    add_count(*b, "--frames", birds->frames, 1, 100'000, "frames per repetition (default: 30)");
    add_switch(*b, "--readback", birds->readback, "read the poses back every frame (default: off)");
    add_text(*b, "--pose-layouts", birds->pose_layouts, "LIST",
             "time the vulkan backend with its poses as records (one BirdPoseGpu per bird), as fields (six arrays of "
             "vec4), or both side by side: records,fields (default: records)");
    add_common(*b, birds->common);

    auto chains = std::make_shared<ChainsOptions>();
    CLI::App* ch = bench->add_subcommand("chains", "joint-steps per second on procedural chains, one solver substep per frame");
    add_count(*ch, "--count", chains->count, 1, 2'000'000, "chains, 1 to 2000000 (default: 100000)");
    add_count(*ch, "--chains", chains->chains, 1, 2'000'000, "deprecated: the old spelling of --count, for one release");
    add_count(*ch, "--joints", chains->joints, 2, rods::kMaxChainJoints, "joints per chain (default: 16)");
    add_count(*ch, "--iterations", chains->iterations, 1, 64, "solver iterations per substep (default: 4)");
    add_count(*ch, "--frames", chains->frames, 1, 100'000, "frames (steps of 1/120 s) per repetition (default: 10)");
    add_count(*ch, "--steps", chains->steps, 1, 100'000, "deprecated: the old spelling of --frames, for one release");
    add_text(*ch, "--rod-kernels", chains->rod_kernels, "LIST",
             "time the vulkan backend's rod kernels side by side: per-chain (an invocation per chain, rods_step.comp), "
             "shared-constants (the same with the template's constants in shared memory), per-joint (an invocation per "
             "joint, rods_lanes.comp), e.g. per-chain,shared-constants,per-joint (default: per-chain)");
    add_common(*ch, chains->common);

    auto crowd = std::make_shared<CrowdOptions>();
    CLI::App* cr = bench->add_subcommand("crowd", "frames per second of a crowd of N skinned characters: clips and chains");
    add_scene(*cr, crowd->scene, "scenes/crowd-gltf.json");
    add_count(*cr, "--count", crowd->count, 1, 100'000, "characters, 1 to 100000 (default: 1000)");
    add_count(*cr, "--frames", crowd->frames, 1, 100'000, "frames per repetition (default: 60)");
    add_lod_options(*cr, crowd->lod);
    add_common(*cr, crowd->common);

    std::function<int()> run_flock;
    CLI::App* fl = add_bench_flock(*bench, run_flock);
    std::function<int()> run_view;
    CLI::App* vw = add_bench_view(*bench, run_view);
    std::function<int()> run_ceilings;
    add_bench_ceilings(*bench, run_ceilings);

    return {bench, [=] {
                if (b->parsed()) return bench_birds(*birds);
                if (ch->parsed()) return bench_chains(*chains);
                if (cr->parsed()) return bench_crowd(*crowd);
                if (fl->parsed()) return run_flock();
                if (vw->parsed()) return run_view();
                return run_ceilings();
            }};
}

}  // namespace kodawari::cli
