// The flocking domain (kodawari/domains/flocking.hpp, docs/flocking.md): the flocking
// flocks' birds stepped by their rules on a FlockBackend, each frame's motion handed to
// the bird domain, behind the domain contract (kodawari/simulation/domain.hpp).
#include "kodawari/domains/flocking.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "kodawari/render/renderer.hpp"
#include "vulkan_backends/device_backends.hpp"
#include "domains/flocking/flock_backend.hpp"
#include "domains/flocking/flock_draw.hpp"
#include "domains/flocking/flock_world.hpp"

namespace kodawari {

namespace {

class FlockingDomain final : public Domain {
public:
    explicit FlockingDomain(flocking::FlockWorld world) : world_(std::move(world)), extent_(flocking::draw_extent(world_)) {}

    std::string_view name() const override { return kFlockingDomain; }
    std::string_view instance_noun() const override { return "flocking birds"; }
    // Not cut into shards: a bird's neighbours may be in any shard's range, so every
    // shard simulates the whole flock and the bird domain keeps its range.
    std::uint32_t scene_instances() const override { return 0; }
    void keep_instances(InstanceRange) override {}
    std::vector<std::string> outputs() const override { return {std::string(kFlockingDomain)}; }
    std::vector<std::string> buffers() const override { return {std::string(flock_buffers::agents)}; }
    // The application's range of the agents' buffer (set_flock_device_agents): after the
    // scene's predators, room for kMaxFlockAgents.
    Result<VulkanBufferRange> buffer(std::string_view name) const override {
        const DeviceSpan agents = backend_ ? backend_->device_agents() : DeviceSpan{};
        if (agents.buffer == nullptr) {
            return make_error(Error::Kind::InvalidInput, "domain \"flocking\": \"" + std::string(name) +
                                                             "\" is not on a Vulkan device (a cpu backend)");
        }
        return vulkan_range(agents);
    }

    Result<void> open(const DomainSetup& setup, std::span<Domain* const>) override {
        switch (setup.kind) {
            case BackendKind::CpuReference: backend_ = flocking::make_reference_flock_backend(); break;
            case BackendKind::Cpu: {
                auto made = flocking::make_cpu_flock_backend(setup.options);
                if (!made) return made.error();
                backend_ = std::move(made).value();
                break;
            }
            case BackendKind::Vulkan: {
                auto made = flocking::make_vulkan_flock_backend(setup.options);
                if (!made) return made.error();
                backend_ = std::move(made).value();
                break;
            }
        }
        return rewind();
    }
    void close() override { backend_.reset(); }
    Result<void> rewind() override {
        frame_ = 0;
        return backend_ ? backend_->load(world_) : Result<void>{};
    }

    std::vector<ChannelInfo> channels() const override {
        return {{std::string(kFlockingMotionChannel), sizeof(gpu::BirdMotionGpu), world_.birds.size(), true}};
    }
    std::uint32_t max_bake_frames() const override {
        constexpr std::uint32_t kChunkMotions = 1u << 18;
        return std::clamp<std::uint32_t>(kChunkMotions / std::max<std::uint32_t>(static_cast<std::uint32_t>(world_.birds.size()), 1u), 1,
                                         kMaxBakeFrames);
    }

    Result<void> step(std::uint32_t first, std::uint32_t frames, std::span<const ChannelOutput> out) override {
        if (!backend_) return {};
        if (device_agents_ > 0) {
            return make_error(Error::Kind::InvalidInput,
                              "domain \"flocking\": " + std::to_string(device_agents_) +
                                  " agents are on the device (set_flock_device_agents), which record() reads and step() "
                                  "cannot: record the frames, or set_flock_device_agents(sim, 0) first");
        }
        if (first != frame_) {
            return make_error(Error::Kind::InvalidInput, "domain \"flocking\": step(" + std::to_string(first) + ") after frame " +
                                                             std::to_string(frame_) + " (frames go in order from 0)");
        }
        const std::size_t n = world_.birds.size(), f = world_.flocks.size();
        const std::size_t a = world_.scene_agents() + app_agents_.size();
        motion_.resize(std::size_t{frames} * n);
        std::uint32_t k0 = 0;
        if (first == 0 && frames > 0) {
            std::copy(world_.first.begin(), world_.first.end(), motion_.begin());
            k0 = 1;
        }
        const std::uint32_t advance = frames - k0;
        if (advance > 0) {
            flocks_.resize(std::size_t{advance} * f);
            agents_.resize(std::size_t{advance} * a);
            for (std::uint32_t k = 0; k < advance; ++k) {
                frame_inputs(first + k0 + k, std::span(flocks_).subspan(std::size_t{k} * f, f), std::span(agents_).subspan(std::size_t{k} * a, a));
            }
            KW_TRY(backend_->advance(advance, flocks_, agents_, std::span(motion_).subspan(std::size_t{k0} * n)));
        }
        frame_ += frames;
        for (const ChannelOutput& channel : out) {
            if (channel.name == kFlockingMotionChannel) std::memcpy(channel.bytes.data(), motion_.data(), channel.bytes.size());
        }
        return {};
    }

    // One frame into the application's command buffer: the frame's inputs go through the
    // backend's staging ring and its motion stays on the device, where the bird domain's
    // record copies it from (motion_buffer()); nothing is read back.
    Result<void> record(std::uint32_t frame, compute::Recording& recording) override {
        if (!backend_) return {};
        if (frame != frame_) {
            return make_error(Error::Kind::InvalidInput, "domain \"flocking\": record(" + std::to_string(frame) + ") after frame " +
                                                             std::to_string(frame_) + " (frames go in order from 0)");
        }
        if (frame == 0) {
            KW_TRY(backend_->record(recording, true, {}, {}, 0));
        } else {
            flocks_.resize(world_.flocks.size());
            agents_.resize(world_.scene_agents() + app_agents_.size());
            frame_inputs(frame, flocks_, agents_);
            KW_TRY(backend_->record(recording, false, flocks_, agents_, device_agents_));
        }
        frame_ = frame + 1;
        motion_.clear();  // this frame's motion is on the device only
        return {};
    }

    std::string device() const override { return backend_ ? backend_->device() : std::string(); }
    std::uint32_t validation_messages() const override { return backend_ ? backend_->validation_messages() : 0; }
    // The birds draw themselves (the bird domain); this domain draws the obstacles, the
    // scene's and those the application placed last (set_flock_agents), through
    // render::Draw. The agents on the device (set_flock_device_agents) are not read back.
    Result<void> show_on(render::Renderer&, bool) override { return {}; }
    Result<void> draw_on(render::Renderer& renderer, DrawSource, bool) override {
        render::Draw& draw = renderer;
        flocking::draw_obstacles(draw, world_.fixed_agents, extent_);
        flocking::draw_obstacles(draw, app_agents_, extent_);
        return {};
    }

    std::span<const gpu::BirdMotionGpu> motion() const { return motion_; }
    const compute::Buffer* motion_buffer() const { return backend_ ? backend_->motion_buffer() : nullptr; }
    FlockingTiming timing() const { return backend_ ? backend_->timing() : FlockingTiming{}; }
    Result<FlockingTiming> profile(std::uint32_t frames) {
        if (!backend_) return make_error(Error::Kind::InvalidInput, "profile_flocking: domain: the flocking domain is not open");
        flocks_.resize(world_.flocks.size());
        agents_.resize(world_.scene_agents() + app_agents_.size());
        frame_inputs(frame_, flocks_, agents_);
        return backend_->profile(frames, flocks_, agents_);
    }
    // The application's agents: from host arrays, or that many on the device; each
    // replaces the other.
    void set_agents(std::vector<gpu::FlockAgentGpu> agents) {
        app_agents_ = std::move(agents);
        device_agents_ = 0;
    }
    Result<void> set_device_agents(std::uint32_t count) {
        if (count > 0 && (backend_ == nullptr || backend_->device_agents().buffer == nullptr)) {
            return make_error(Error::Kind::InvalidInput, "set_flock_device_agents: agents on the device need the vulkan backend "
                                                         "(this simulation runs on the CPU): set_flock_agents takes them from "
                                                         "host arrays");
        }
        app_agents_.clear();
        device_agents_ = count;
        return {};
    }

private:
    // Frame `frame`'s flock parameters and agents: the scene's (FlockWorld::frame_inputs),
    // then the application's (set_flock_agents), which `agents` has room for.
    void frame_inputs(std::uint32_t frame, std::span<gpu::FlockParamsGpu> flocks, std::span<gpu::FlockAgentGpu> agents) const {
        const std::size_t scene_agents = world_.scene_agents();
        world_.frame_inputs(frame, flocks, agents.first(scene_agents));
        std::copy(app_agents_.begin(), app_agents_.end(), agents.begin() + static_cast<std::ptrdiff_t>(scene_agents));
    }

    flocking::FlockWorld world_;
    flocking::DrawExtent extent_;  // where a plane obstacle is drawn
    std::unique_ptr<flocking::FlockBackend> backend_;
    std::uint32_t frame_ = 0;
    std::vector<gpu::BirdMotionGpu> motion_;
    std::vector<gpu::FlockParamsGpu> flocks_;
    std::vector<gpu::FlockAgentGpu> agents_;
    std::vector<gpu::FlockAgentGpu> app_agents_;  // set_flock_agents()
    std::uint32_t device_agents_ = 0;              // set_flock_device_agents()
};

// One application agent as the kernels take it, or an error naming `what` (the argument,
// with its trailing dot) and the member.
Result<gpu::FlockAgentGpu> agent_gpu(const FlockAgent& a, const std::string& what) {
    auto bad = [&](const char* member, const char* expected) {
        return make_error(Error::Kind::InvalidInput, what + member + ": expected " + expected);
    };
    using Kind = FlockAgent::Kind;
    if (static_cast<std::uint32_t>(a.kind) > static_cast<std::uint32_t>(Kind::Plane)) {
        return bad("kind", "Predator, Attractor, Obstacle, Capsule or Plane (0 to 4)");
    }
    const bool obstacle = a.kind == Kind::Obstacle || a.kind == Kind::Capsule || a.kind == Kind::Plane;
    for (int c = 0; c < 3; ++c) {
        if (!(std::abs(a.position[c]) <= 1e6f)) return bad("position", "3 numbers in [-1e6, 1e6] m");
        if (!(std::abs(a.velocity[c]) <= 1000.0f)) return bad("velocity", "3 numbers in [-1000, 1000] m/s");
        if (a.kind == Kind::Capsule && !(std::abs(a.end[c]) <= 1e6f)) return bad("end", "3 numbers in [-1e6, 1e6] m");
        if (a.kind == Kind::Plane && !(std::abs(a.normal[c]) <= 1e6f)) return bad("normal", "3 finite numbers");
    }
    // A plane has no extent to bound (the kernels read no radius for it).
    if (a.kind != Kind::Plane && !(a.radius > 0.0f && a.radius <= 1e4f)) return bad("radius", "a number in (0, 10000] m");
    if (!(a.weight >= 0.0f && a.weight <= 1000.0f)) return bad("weight", "a number in [0, 1000] m/s^2");
    if (!(a.margin > 0.0f && a.margin <= 1000.0f)) return bad("margin", "a number in (0, 1000] m");
    const float normal_length = glm::length(a.normal);
    if (a.kind == Kind::Plane && !(normal_length > 1e-6f)) return bad("normal", "a direction (length above 1e-6)");
    // The kernels' encoding (shared/flocking.h), as the scene's obstacles are written
    // (flock_world.cpp): a capsule's other end and a plane's unit normal in `velocity`.
    gpu::FlockAgentGpu g{};
    g.position = {a.position.x, a.position.y, a.position.z, a.kind == Kind::Plane ? 0.0f : a.radius};
    const float kind = a.kind == Kind::Predator    ? KW_FLOCK_AGENT_REPELLER
                       : a.kind == Kind::Attractor ? KW_FLOCK_AGENT_ATTRACTOR
                       : a.kind == Kind::Obstacle  ? KW_FLOCK_AGENT_SPHERE
                       : a.kind == Kind::Capsule   ? KW_FLOCK_AGENT_CAPSULE
                                                   : KW_FLOCK_AGENT_PLANE;
    g.kind_weight = {kind, a.weight, obstacle ? a.margin : 0.0f, 0.0f};
    const glm::vec3 v = a.kind == Kind::Capsule ? a.end : a.kind == Kind::Plane ? a.normal / normal_length : a.velocity;
    g.velocity = {v.x, v.y, v.z, 0.0f};
    return g;
}

}  // namespace

Result<std::unique_ptr<Domain>> make_flocking_domain(const Scene& scene, const birds::BirdWorld& world) {
    if (world.driven == 0) return std::unique_ptr<Domain>();
    auto built = flocking::build_flock_world(scene, world);
    if (!built) return built.error();
    return std::unique_ptr<Domain>(std::make_unique<FlockingDomain>(std::move(built).value()));
}

Result<gpu::FlockAgentGpu> encode_flock_agent(const FlockAgent& agent) { return agent_gpu(agent, "encode_flock_agent: agent."); }

Result<void> set_flock_device_agents(Simulation& sim, std::uint32_t count) {
    if (count > kMaxFlockAgents) {
        return make_error(Error::Kind::InvalidInput, "set_flock_device_agents: count: " + std::to_string(count) +
                                                         " agents; at most " + std::to_string(kMaxFlockAgents));
    }
    auto* flock = dynamic_cast<FlockingDomain*>(sim.domain(kFlockingDomain));
    if (flock == nullptr) return {};
    // Agents on the device are read by record() only (step() refuses them): a simulation
    // that cannot record would be left with neither.
    if (count > 0 && sim.backend() == BackendKind::Vulkan && !sim.can_record()) {
        return make_error(Error::Kind::InvalidInput,
                          "set_flock_device_agents: agents on the device are read by record(), which needs the "
                          "application's device (SimulationOptions::options.context; in C, the backend options' "
                          "vulkan_device); this simulation opened its own: set_flock_agents takes them from host arrays");
    }
    return flock->set_device_agents(count);
}

Result<void> set_flock_agents(Simulation& sim, std::span<const FlockAgent> agents) {
    if (agents.size() > kMaxFlockAgents) {
        return make_error(Error::Kind::InvalidInput, "set_flock_agents: agents: " + std::to_string(agents.size()) +
                                                         " agents; at most " + std::to_string(kMaxFlockAgents));
    }
    std::vector<gpu::FlockAgentGpu> converted;
    for (std::size_t i = 0; i < agents.size(); ++i) {
        auto g = agent_gpu(agents[i], "set_flock_agents: agents[" + std::to_string(i) + "].");
        if (!g) return g.error();
        converted.push_back(g.value());
    }
    if (auto* flock = dynamic_cast<FlockingDomain*>(sim.domain(kFlockingDomain))) flock->set_agents(std::move(converted));
    return {};
}

std::span<const gpu::BirdMotionGpu> flocking_motion(const Domain& domain) {
    const auto* flock = dynamic_cast<const FlockingDomain*>(&domain);
    return flock ? flock->motion() : std::span<const gpu::BirdMotionGpu>{};
}

FlockingTiming flocking_timing(const Domain& domain) {
    const auto* flock = dynamic_cast<const FlockingDomain*>(&domain);
    return flock ? flock->timing() : FlockingTiming{};
}

Result<FlockingTiming> profile_flocking(Domain& domain, std::uint32_t frames) {
    auto* flock = dynamic_cast<FlockingDomain*>(&domain);
    if (flock == nullptr) {
        return make_error(Error::Kind::InvalidInput, "profile_flocking: domain: expected the flocking domain, got \"" +
                                                         std::string(domain.name()) + "\"");
    }
    if (frames == 0) return make_error(Error::Kind::InvalidInput, "profile_flocking: frames: expected at least 1, got 0");
    return flock->profile(frames);
}

namespace flocking {

const compute::Buffer* flocking_motion_buffer(const Domain& domain) {
    const auto* flock = dynamic_cast<const FlockingDomain*>(&domain);
    return flock ? flock->motion_buffer() : nullptr;
}

}  // namespace flocking

}  // namespace kodawari
