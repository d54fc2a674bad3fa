// The Simulation facade (kodawari/simulation/simulation.hpp): the frame protocol that `run`,
// `render`, `view` and `bench` each sequenced on their own before (issue 19), in one
// place, over the domain contract (kodawari/simulation/domain.hpp, issue 31): it names no domain.
#include "kodawari/simulation/simulation.hpp"

#include <algorithm>
#include <cassert>

#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/vulkan/compute.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"
#include "kodawari/render/renderer.hpp"

namespace kodawari {

struct Simulation::Impl {
    Scene scene;
    SimulationOptions options;
    BackendKind kind = BackendKind::Cpu;
    bool application_device = false;  // SimulationOptions::options.context given: record() can run
    std::string fallback_reason;
    std::uint32_t frames = 1;
    ShardInfo shard;
    // The domains in their step order, and each one's producers (its inputs' domains).
    std::vector<std::unique_ptr<Domain>> owned;
    std::vector<Domain*> domains;
    std::vector<std::vector<Domain*>> producers;
    // Every domain's channels as opened, and the domain (index into `domains`) of each:
    // step() matches outputs against them without asking the domains every frame.
    std::vector<ChannelInfo> channels;
    std::vector<std::size_t> channel_domain;
    std::optional<std::uint32_t> current;

    [[nodiscard]] Result<void> open_domains() {
        const DomainSetup setup{kind, options.options, options.device_inputs};
        for (std::size_t i = 0; i < domains.size(); ++i) KW_TRY(domains[i]->open(setup, producers[i]));
        channels.clear();
        channel_domain.clear();
        for (std::size_t i = 0; i < domains.size(); ++i) {
            for (ChannelInfo& info : domains[i]->channels()) {
                channels.push_back(std::move(info));
                channel_domain.push_back(i);
            }
        }
        return {};
    }

    void close_domains() {
        for (auto it = domains.rbegin(); it != domains.rend(); ++it) (*it)->close();
    }

    [[nodiscard]] bool shares_device_with(const render::Renderer& renderer) const {
        return kind == BackendKind::Vulkan && options.options.context != nullptr &&
               options.options.context == renderer.device_context();
    }
};

Simulation::Simulation(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Simulation::~Simulation() {
    // Readers before their producers: a reader may hold what a producer lent it.
    if (impl_) impl_->close_domains();
}

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

ShardPart ShardInfo::part(std::string_view instances) const {
    for (const ShardPart& p : parts) {
        if (p.instances == instances) return p;
    }
    return {std::string(instances), {}, 0};
}

Result<std::unique_ptr<Simulation>> Simulation::create(Scene scene, const SimulationOptions& options,
                                                       std::vector<std::unique_ptr<Domain>> domains) {
    if (options.shard.count == 0 || options.shard.index >= options.shard.count) {
        return make_error(Error::Kind::InvalidInput, "SimulationOptions::shard: expected index < count, got " +
                                                         std::to_string(options.shard.index) + " of " +
                                                         std::to_string(options.shard.count));
    }
    if (options.frames && (*options.frames == 0 || *options.frames > kMaxSimulationFrames)) {
        return make_error(Error::Kind::InvalidInput, "SimulationOptions::frames: expected an integer in [1, " +
                                                         std::to_string(kMaxSimulationFrames) + "], got " +
                                                         std::to_string(*options.frames));
    }
    for (std::size_t i = 0; i < domains.size(); ++i) {
        if (!domains[i]) {
            return make_error(Error::Kind::InvalidInput, "Simulation::create: domains[" + std::to_string(i) + "] is null");
        }
    }
    auto impl = std::make_unique<Impl>();
    impl->options = options;
    impl->frames = options.frames.value_or(scene.frame_count());
    auto built = build_scene_domains(scene, impl->frames);
    if (!built) return built.error();
    impl->owned = std::move(built).value();
    for (auto& domain : domains) impl->owned.push_back(std::move(domain));
    impl->scene = std::move(scene);

    std::vector<const Domain*> given;
    for (const auto& domain : impl->owned) given.push_back(domain.get());
    auto order = order_domains(given);
    if (!order) return order.error();
    for (std::size_t i : order.value()) impl->domains.push_back(impl->owned[i].get());
    for (Domain* domain : impl->domains) {
        std::vector<Domain*> from;
        for (const std::string& input : domain->inputs()) {
            for (Domain* other : impl->domains) {
                const auto outputs = other->outputs();
                if (std::find(outputs.begin(), outputs.end(), input) != outputs.end()) from.push_back(other);
            }
        }
        impl->producers.push_back(std::move(from));
    }

    // Cut after building: the random draws are the whole scene's (Shard).
    impl->shard.shard = options.shard;
    for (Domain* domain : impl->domains) {
        const std::uint32_t n = domain->scene_instances();
        const InstanceRange range = shard_range(n, options.shard);
        domain->keep_instances(range);
        impl->shard.parts.push_back({std::string(domain->instance_noun()), range, n});
    }

    // One Vulkan device for every domain, so that their buffers meet there (one domain's
    // outputs feed another's inputs, a renderer draws the state); "auto" falls back to the
    // CPU when none opens, but not when a device was asked for by name or index: the
    // caller meant that device, and running elsewhere would hide the mistake.
    // Nor does "auto" run on a CPU-type device (lavapipe) unless it was named: the cpu
    // backend is several times faster there (auto_passes_over(), issue 38).
    impl->kind = options.backend.value_or(BackendKind::Vulkan);
    impl->application_device = options.options.context != nullptr;
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
    if (auto opened = impl->open_domains(); !opened) {
        // "auto" also falls back when a device opened but cannot run this scene (a buffer
        // larger than it can bind: Unsupported, naming the buffer and the sizes); the CPU
        // backends have no such limit. Any other error (a lost device, a bug) is reported.
        const bool automatic = !options.backend && impl->kind == BackendKind::Vulkan && !options.options.context;
        if (!automatic || opened.error().kind != Error::Kind::Unsupported) {
            impl->close_domains();
            return opened.error();
        }
        impl->close_domains();
        impl->options.options.context = nullptr;
        impl->kind = BackendKind::Cpu;
        impl->fallback_reason = opened.error().message;
        if (auto reopened = impl->open_domains(); !reopened) {
            impl->close_domains();
            return reopened.error();
        }
    }
    return std::unique_ptr<Simulation>(new Simulation(std::move(impl)));
}

const Scene& Simulation::scene() const { return impl_->scene; }
std::span<Domain* const> Simulation::domains() const { return impl_->domains; }
std::span<const ChannelInfo> Simulation::channels() const { return impl_->channels; }
const ShardInfo& Simulation::shard() const { return impl_->shard; }
BackendKind Simulation::backend() const { return impl_->kind; }
bool Simulation::can_record() const { return impl_->kind == BackendKind::Vulkan && impl_->application_device; }
const std::string& Simulation::fallback_reason() const { return impl_->fallback_reason; }
std::uint32_t Simulation::frame_count() const { return impl_->frames; }
std::optional<std::uint32_t> Simulation::frame() const { return impl_->current; }

Domain* Simulation::domain(std::string_view name) const {
    for (Domain* domain : impl_->domains) {
        if (domain->name() == name) return domain;
    }
    return nullptr;
}

std::string Simulation::device() const {
    for (const Domain* domain : impl_->domains) {
        if (std::string device = domain->device(); !device.empty()) return device;
    }
    return std::string(backend_name(impl_->kind));
}

std::uint32_t Simulation::validation_messages() const {
    std::uint32_t n = 0;
    for (const Domain* domain : impl_->domains) n = std::max(n, domain->validation_messages());
    return n;
}

Result<void> Simulation::step(std::uint32_t frames, std::span<const ChannelOutput> out) {
    Impl& s = *impl_;
    const std::uint32_t first = s.current ? *s.current + 1 : 0;
    if (frames == 0 || first + std::uint64_t{frames} > s.frames) {
        return make_error(Error::Kind::InvalidInput, "Simulation::step: " + std::to_string(frames) + " frames from frame " +
                                                         std::to_string(first) + " pass the last frame (" +
                                                         std::to_string(s.frames - 1) + ")");
    }
    // Every output names a channel of one domain and holds frames x its elements.
    std::vector<std::vector<ChannelOutput>> per_domain(s.domains.size());
    for (const ChannelOutput& channel : out) {
        const auto at = std::find_if(s.channels.begin(), s.channels.end(),
                                     [&](const ChannelInfo& info) { return info.name == channel.name; });
        if (at == s.channels.end()) {
            return make_error(Error::Kind::InvalidInput,
                              "Simulation::step: no domain has a channel \"" + std::string(channel.name) + "\"");
        }
        const ChannelInfo& info = *at;
        const std::uint64_t bytes = std::uint64_t{frames} * info.elements * info.element_bytes;
        if (channel.bytes.size() != bytes) {
            return make_error(Error::Kind::InvalidInput,
                              "Simulation::step: channel \"" + info.name + "\" must hold frames x elements = " +
                                  std::to_string(std::uint64_t{frames} * info.elements) + " entries of " +
                                  std::to_string(info.element_bytes) + " bytes (" + std::to_string(bytes) +
                                  " bytes), got " + std::to_string(channel.bytes.size()) + " bytes");
        }
        per_domain[s.channel_domain[static_cast<std::size_t>(at - s.channels.begin())]].push_back(channel);
    }
    for (std::size_t d = 0; d < s.domains.size(); ++d) KW_TRY(s.domains[d]->step(first, frames, per_domain[d]));
    s.current = first + frames - 1;
    return {};
}

Result<void> Simulation::record(compute::Recording& recording) {
    Impl& s = *impl_;
    if (s.kind != BackendKind::Vulkan) {
        return make_error(Error::Kind::InvalidInput, "Simulation::record: records Vulkan commands; this simulation runs on the " +
                                                         std::string(backend_name(s.kind)) + " backend");
    }
    if (&recording.device() != s.options.options.context.get()) {
        return make_error(Error::Kind::InvalidInput,
                          "Simulation::record: the recording is on another device than the simulation's "
                          "(borrow_command_buffer on SimulationOptions::options.context)");
    }
    const std::uint32_t frame = s.current ? *s.current + 1 : 0;
    if (frame >= s.frames) {
        return make_error(Error::Kind::InvalidInput, "Simulation::record: frame " + std::to_string(frame) +
                                                         " is past the last frame (" + std::to_string(s.frames - 1) + ")");
    }
    for (Domain* domain : s.domains) KW_TRY(domain->record(frame, recording));
    s.current = frame;
    return {};
}

Result<void> Simulation::record(VkCommandBuffer cmd) {
    Impl& s = *impl_;
    if (s.kind != BackendKind::Vulkan) {
        return make_error(Error::Kind::InvalidInput, "Simulation::record: records Vulkan commands; this simulation runs on the " +
                                                         std::string(backend_name(s.kind)) + " backend");
    }
    auto recording = borrow_command_buffer(*s.options.options.context, cmd);
    if (!recording) return recording.error();
    return record(recording.value());
}

Result<VulkanBufferRange> Simulation::buffer(std::string_view name) const {
    std::string names;
    for (const Domain* domain : impl_->domains) {
        for (const std::string& own : domain->buffers()) {
            if (own == name) return domain->buffer(name);
            names += (names.empty() ? "" : ", ") + own;
        }
    }
    return make_error(Error::Kind::InvalidInput, "Simulation::buffer: no domain has a buffer named \"" + std::string(name) +
                                                     "\" (" + (names.empty() ? std::string("none has buffers") : "they have " + names) + ")");
}

Result<void> Simulation::seek(std::uint32_t target) {
    Impl& s = *impl_;
    target = std::min(target, s.frames - 1);
    if (s.current && *s.current == target) return {};
    if (s.current && *s.current > target) {
        s.current.reset();
        for (Domain* domain : s.domains) KW_TRY(domain->rewind());
    }
    const std::uint32_t first = s.current ? *s.current + 1 : 0;
    for (std::uint32_t f = first; f <= target; ++f) KW_TRY(step(1));
    return {};
}

Result<void> Simulation::show_on(render::Renderer& renderer) {
    Impl& s = *impl_;
    // What another simulation showed on this renderer goes first.
    KW_TRY(renderer.clear_layers());
    renderer.clear_draws();
    for (Domain* domain : s.domains) KW_TRY(domain->show_on(renderer, s.shares_device_with(renderer)));
    return {};
}

Result<void> Simulation::draw_on(render::Renderer& renderer, DrawSource source) {
    Impl& s = *impl_;
    // What the domains drew through render::Draw for the previous frame goes.
    renderer.clear_draws();
    for (Domain* domain : s.domains) KW_TRY(domain->draw_on(renderer, source, s.shares_device_with(renderer)));
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
