// The Simulation facade (kodawari/simulation.hpp): the frame protocol that `run`,
// `render`, `view` and `bench` each sequenced on their own before (issue 19), in one place.
#include "kodawari/backend_factory.hpp"
#include "kodawari/simulation.hpp"

#include <algorithm>
#include <cassert>
#include <chrono>

#include "kodawari/crowd_animator.hpp"
#include "kodawari/render/renderer.hpp"

namespace kodawari {

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

struct Simulation::Impl {
    Scene scene;
    birds::BirdWorld bird_world;
    std::optional<RodScene> rod_scene;
    SimulationOptions options;
    BackendKind kind = BackendKind::Cpu;
    std::string fallback_reason;
    std::uint32_t frames = 1;
    ShardInfo shard;

    std::unique_ptr<BirdBackend> birds;
    std::unique_ptr<RodBackend> rods;
    std::optional<CrowdAnimator> animator;

    std::optional<rods::Camera> view_camera;
    rods::RodFrame input;
    rods::RodFrame host_input;
    std::optional<std::uint32_t> host_input_frame;
    std::optional<std::uint32_t> current;
    // The last frame's bird poses on the host, for drawing from a CPU backend.
    bool keep_poses = false;
    std::vector<gpu::BirdPose> last_poses;
    std::vector<gpu::BirdPose> poses_scratch;
    ChainSnapshot snapshot;  // DrawSource::ReadBack
    SimulationTiming timing;

    [[nodiscard]] Result<void> open_backends() {
        if (!bird_world.birds.empty()) {
            auto made = make_bird_backend(kind, options.options);
            if (!made) return made.error();
            birds = std::move(made).value();
            KW_TRY(birds->load(bird_world));
        }
        // A shard may hold none of the characters: nothing to step then.
        if (rod_scene && !rod_scene->instances.empty()) {
            auto made = make_rod_backend(kind, options.options);
            if (!made) return made.error();
            rods = std::move(made).value();
            // Rigged characters' clips are evaluated by the pose backend of the same kind.
            auto created = CrowdAnimator::create(*rod_scene, kind, options.options);
            if (!created) return created.error();
            animator.emplace(std::move(created).value());
        }
        return {};
    }

    // Frame `f` of the chains: the kinematic input, then the initial state (f == 0) or one step.
    [[nodiscard]] Result<void> chain_frame(std::uint32_t f) {
        KW_TRY(animator->frame(f, input));
        timing.pose_ms += animator->last_pose_ms();
        if (view_camera) input.camera = *view_camera;
        const auto start = std::chrono::steady_clock::now();
        KW_TRY(f == 0 ? rods->load(rod_scene->world, input) : rods->step(input));
        if (f == 0 && options.rod_inputs_on_device) {
            // From now on the rigged characters' input is written where the chains step
            // (when the pose and rod backends share a Vulkan device; nothing otherwise).
            auto took = animator->write_inputs_on(*rods);
            if (!took) return took.error();
        }
        (f < 2 ? timing.chain_warmup_seconds : timing.chain_seconds) += seconds_since(start);
        if (f >= 2 && rods->last_gpu_ms() >= 0.0) timing.chain_gpu_ms += rods->last_gpu_ms();
        return {};
    }

    [[nodiscard]] Result<void> bird_frames(std::uint32_t n, const StepOutput& out) {
        FrameOutput frame_out{out.bird_poses, out.bird_diag};
        const bool keep = keep_poses && out.bird_poses.empty();
        if (keep) {
            poses_scratch.resize(std::size_t{n} * bird_world.birds.size());
            frame_out.poses = poses_scratch;
        }
        const auto start = std::chrono::steady_clock::now();
        KW_TRY(birds->simulate(n, frame_out));
        if (timing.bird_first_frames == 0) {
            timing.bird_first_seconds = seconds_since(start);
            timing.bird_first_frames = n;
            timing.bird_first_gpu_ms = birds->last_gpu_ms();
        } else {
            timing.bird_seconds += seconds_since(start);
            timing.bird_frames += n;
            if (birds->last_gpu_ms() >= 0.0) {
                timing.bird_gpu_ms += birds->last_gpu_ms();
            } else {
                timing.bird_gpu_timed = false;
            }
        }
        if (keep_poses) {
            const std::size_t count = bird_world.birds.size();
            const auto last = frame_out.poses.subspan((std::size_t{n} - 1) * count, count);
            last_poses.assign(last.begin(), last.end());
        }
        return {};
    }

    [[nodiscard]] Result<void> rewind() {
        current.reset();
        host_input_frame.reset();
        if (birds) KW_TRY(birds->load(bird_world));
        return {};
    }

    [[nodiscard]] bool shares_device_with(const render::Renderer& renderer) const {
        return kind == BackendKind::Vulkan && options.options.context != nullptr &&
               options.options.context == renderer.device_context();
    }
};

Simulation::Simulation(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Simulation::~Simulation() = default;

Result<std::unique_ptr<Simulation>> Simulation::open(const std::string& path, const SimulationOptions& options) {
    auto scene = load_scene(path);
    if (!scene) return scene.error();
    return create(std::move(scene).value(), options);
}

InstanceRange shard_range(std::uint32_t n, Shard shard) {
    assert(shard.count >= 1 && shard.index < shard.count);
    const auto at = [&](std::uint32_t i) {
        return static_cast<std::uint32_t>(std::uint64_t{n} * i / shard.count);
    };
    return {at(shard.index), at(shard.index + 1)};
}

Result<SceneWorlds> build_scene_worlds(const Scene& scene, std::optional<std::uint32_t> frames) {
    if (frames && *frames == 0) {
        return make_error(Error::Kind::InvalidInput, "SimulationOptions::frames: expected at least 1 frame, got 0");
    }
    SceneWorlds worlds;
    auto birds = build_bird_world(scene);
    if (!birds) return birds.error();
    worlds.birds = std::move(birds).value();
    worlds.frames = frames.value_or(scene.frame_count());
    worlds.birds.frames = worlds.frames;
    if (!scene.characters.empty()) {
        auto built = build_rod_scene(scene);
        if (!built) return built.error();
        worlds.rods.emplace(std::move(built).value());
    }
    return worlds;
}

Result<std::unique_ptr<Simulation>> Simulation::create(Scene scene, const SimulationOptions& options) {
    if (options.shard.count == 0 || options.shard.index >= options.shard.count) {
        return make_error(Error::Kind::InvalidInput, "SimulationOptions::shard: expected index < count, got " +
                                                         std::to_string(options.shard.index) + " of " +
                                                         std::to_string(options.shard.count));
    }
    auto worlds = build_scene_worlds(scene, options.frames);
    if (!worlds) return worlds.error();
    auto impl = std::make_unique<Impl>();
    impl->options = options;
    impl->frames = worlds.value().frames;
    impl->bird_world = std::move(worlds.value().birds);
    impl->scene = std::move(scene);
    // Cut after building: the random draws are the whole scene's (Shard).
    ShardInfo& shard = impl->shard;
    shard.shard = options.shard;
    shard.scene_birds = static_cast<std::uint32_t>(impl->bird_world.birds.size());
    shard.birds = shard_range(shard.scene_birds, options.shard);
    if (options.shard.count > 1) {
        auto& birds = impl->bird_world.birds;
        birds.erase(birds.begin() + shard.birds.end, birds.end());
        birds.erase(birds.begin(), birds.begin() + shard.birds.begin);
    }
    if (auto& rods = worlds.value().rods) {
        shard.scene_characters = static_cast<std::uint32_t>(rods->instances.size());
        shard.characters = shard_range(shard.scene_characters, options.shard);
        if (options.shard.count > 1) {
            impl->rod_scene.emplace(rods->slice(shard.characters.begin, shard.characters.end));
        } else {
            impl->rod_scene.emplace(std::move(*rods));
        }
    }

    // One Vulkan device for every backend, so that their buffers meet there (the pose
    // matrices feed the rod input, a renderer draws the state); "auto" falls back to the
    // CPU when none opens, but not when a device was asked for by name or index: the
    // caller meant that device, and running elsewhere would hide the mistake.
    // Nor does "auto" run on a CPU-type device (lavapipe) unless it was named: the cpu
    // backend is several times faster there (auto_passes_over(), issue 38).
    impl->kind = options.backend.value_or(BackendKind::Vulkan);
    if (impl->kind == BackendKind::Vulkan && !impl->options.options.context) {
        auto device = options.backend ? open_shared_device(impl->options.options)
                                      : open_auto_device(impl->options.options, impl->fallback_reason);
        if (!device) return device.error();
        if (device.value()) {
            impl->options.options.context = std::move(device).value();
        } else {
            impl->kind = BackendKind::Cpu;
        }
    }
    if (auto opened = impl->open_backends(); !opened) {
        // "auto" also falls back when a device opened but cannot run this scene (a buffer
        // larger than it can bind: Unsupported, naming the buffer and the sizes); the CPU
        // backends have no such limit. Any other error (a lost device, a bug) is reported.
        const bool automatic = !options.backend && impl->kind == BackendKind::Vulkan && !options.options.context;
        if (!automatic || opened.error().kind != Error::Kind::Unsupported) return opened.error();
        impl->animator.reset();
        impl->rods.reset();
        impl->birds.reset();
        impl->options.options.context = nullptr;
        impl->kind = BackendKind::Cpu;
        impl->fallback_reason = opened.error().message;
        KW_TRY(impl->open_backends());
    }
    return std::unique_ptr<Simulation>(new Simulation(std::move(impl)));
}

const Scene& Simulation::scene() const { return impl_->scene; }
const birds::BirdWorld& Simulation::bird_world() const { return impl_->bird_world; }
const ShardInfo& Simulation::shard() const { return impl_->shard; }
const RodScene* Simulation::rod_scene() const { return impl_->rod_scene ? &*impl_->rod_scene : nullptr; }
BackendKind Simulation::backend() const { return impl_->kind; }
const std::string& Simulation::fallback_reason() const { return impl_->fallback_reason; }
std::uint32_t Simulation::frame_count() const { return impl_->frames; }
std::optional<std::uint32_t> Simulation::frame() const { return impl_->current; }
const SimulationTiming& Simulation::timing() const { return impl_->timing; }
void Simulation::set_view_camera(std::optional<rods::Camera> camera) { impl_->view_camera = camera; }
void Simulation::keep_bird_poses(bool keep) { impl_->keep_poses = keep; }
const rods::RodFrame& Simulation::chain_input() const { return impl_->input; }

std::string Simulation::device() const {
    if (impl_->rods) return impl_->rods->device();
    if (impl_->birds) return impl_->birds->device();
    return std::string(backend_name(impl_->kind));
}

bool Simulation::rod_inputs_on_device() const {
    return impl_->animator && impl_->animator->writes_inputs_on_device();
}

std::uint32_t Simulation::validation_messages() const {
    std::uint32_t n = 0;
    if (impl_->birds) n = std::max(n, impl_->birds->validation_messages());
    if (impl_->rods) n = std::max(n, impl_->rods->validation_messages());
    if (impl_->animator) n = std::max(n, impl_->animator->validation_messages());
    return n;
}

Result<void> Simulation::step(std::uint32_t frames, const StepOutput& out) {
    Impl& s = *impl_;
    const std::uint32_t first = s.current ? *s.current + 1 : 0;
    if (frames == 0 || first + std::uint64_t{frames} > s.frames) {
        return make_error(Error::Kind::InvalidInput, "Simulation::step: " + std::to_string(frames) + " frames from frame " +
                                                         std::to_string(first) + " pass the last frame (" +
                                                         std::to_string(s.frames - 1) + ")");
    }
    const std::size_t entries = std::size_t{frames} * s.bird_world.birds.size();
    if ((!out.bird_poses.empty() && out.bird_poses.size() != entries) || (!out.bird_diag.empty() && out.bird_diag.size() != entries)) {
        return make_error(Error::Kind::InvalidInput, "Simulation::step: StepOutput spans must hold frames x birds = " +
                                                         std::to_string(entries) + " entries or be empty");
    }
    if (s.birds) KW_TRY(s.bird_frames(frames, out));
    if (s.rods) {
        for (std::uint32_t f = first; f < first + frames; ++f) KW_TRY(s.chain_frame(f));
    }
    s.current = first + frames - 1;
    return {};
}

Result<void> Simulation::seek(std::uint32_t target) {
    Impl& s = *impl_;
    target = std::min(target, s.frames - 1);
    if (s.current && *s.current == target) return {};
    if (s.current && *s.current > target) KW_TRY(s.rewind());
    const std::uint32_t first = s.current ? *s.current + 1 : 0;
    for (std::uint32_t f = first; f <= target; ++f) KW_TRY(step(1));
    return {};
}

Result<void> Simulation::read_chains(ChainSnapshot& out) {
    if (!impl_->rods) return {};
    return impl_->rods->read(out);
}

Result<const rods::RodFrame*> Simulation::host_chain_input() {
    Impl& s = *impl_;
    if (!s.animator || !s.animator->writes_inputs_on_device() || !s.current) return &s.input;
    if (s.host_input_frame != s.current) {
        KW_TRY(s.animator->host_frame(*s.current, s.host_input));
        s.host_input.camera = s.input.camera;
        s.host_input_frame = s.current;
    }
    return &s.host_input;
}

Result<void> Simulation::show_on(render::Renderer& renderer) {
    Impl& s = *impl_;
    KW_TRY(renderer.set_chains(s.rods ? &s.rod_scene->world : nullptr));
    KW_TRY(renderer.set_skinned(s.rods ? &*s.rod_scene : nullptr));
    KW_TRY(renderer.set_birds(s.birds ? &s.bird_world : nullptr));
    // Poses on the host only where the renderer cannot draw them where they are.
    if (s.birds && !s.shares_device_with(renderer)) s.keep_poses = true;
    return {};
}

Result<void> Simulation::draw_on(render::Renderer& renderer, DrawSource source) {
    Impl& s = *impl_;
    const bool on_device = source == DrawSource::Device && s.shares_device_with(renderer);
    if (s.rods) {
        if (source == DrawSource::Device) {
            // The renderer reads back and uploads what is not on its device.
            KW_TRY(renderer.chains_from(*s.rods));
            KW_TRY(renderer.skinned_from(*s.animator, *s.rods, s.current.value_or(0)));
        } else {
            KW_TRY(s.rods->read(s.snapshot));
            KW_TRY(renderer.chains_from(s.snapshot));
            KW_TRY(renderer.skinned_from(s.snapshot, s.current.value_or(0)));
        }
        KW_TRY(renderer.colliders_from(*s.rods, s.input));
    }
    if (s.birds) {
        if (on_device) {
            KW_TRY(renderer.birds_from(*s.birds));
        } else {
            if (s.last_poses.size() != s.bird_world.birds.size()) {
                return make_error(Error::Kind::InvalidInput,
                                  "Simulation::draw_on: the bird poses are not on the renderer's device and were not kept "
                                  "(show_on() before step(), or keep_bird_poses(true))");
            }
            KW_TRY(renderer.birds_from(s.last_poses));
        }
    }
    return {};
}

Result<std::optional<BackendKind>> parse_backend_choice(std::string_view name) {
    if (name == "auto") return std::optional<BackendKind>{};
    for (BackendKind kind : {BackendKind::CpuReference, BackendKind::Cpu, BackendKind::Vulkan}) {
        if (backend_name(kind) == name) return std::optional<BackendKind>{kind};
    }
    return make_error(Error::Kind::InvalidInput,
                      "backend: expected auto, vulkan, cpu or cpu-reference, got \"" + std::string(name) + "\"");
}

}  // namespace kodawari
