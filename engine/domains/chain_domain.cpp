// The chain domain (kodawari/domains/chains.hpp): the characters' chains on a RodBackend,
// fed by their kinematics (CrowdAnimator), behind the domain contract (kodawari/simulation/domain.hpp).
#include "kodawari/domains/chains.hpp"

#include <cassert>
#include <chrono>
#include <cstring>
#include <string>
#include <vector>

#include "vulkan_backends/device_backends.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/vulkan/crowd_animator.hpp"
#include "kodawari/domains/chain_draw.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/rods/lod_budget.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"

namespace kodawari {

namespace {

// A snapshot's array that channel `name` holds (ChainDomain::channels()).
std::span<const std::byte> snapshot_channel(const ChainSnapshot& s, std::string_view name) {
    if (name == kChainPositionsChannel) return std::as_bytes(std::span(s.positions));
    if (name == kChainOrientationsChannel) return std::as_bytes(std::span(s.orientations));
    if (name == kChainRestChannel) return std::as_bytes(std::span(s.rest));
    if (name == kChainViewDirectionsChannel) return std::as_bytes(std::span(s.view_directions));
    assert(name == kChainWeightsChannel);
    return std::as_bytes(std::span(s.weights));
}

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

class ChainDomain final : public Domain {
public:
    explicit ChainDomain(std::optional<RodScene> scene)
        : scene_(std::move(scene)), scene_characters_(scene_ ? static_cast<std::uint32_t>(scene_->instances.size()) : 0) {}

    std::string_view name() const override { return kChainDomain; }
    std::string_view instance_noun() const override { return "characters"; }
    std::uint32_t scene_instances() const override { return scene_characters_; }
    // The chains are read back after each frame (a snapshot of every joint): one frame at
    // a time when the scene has characters, in every shard alike.
    std::uint32_t max_bake_frames() const override { return scene_characters_ > 0 ? 1 : kMaxBakeFrames; }

    std::vector<ChannelInfo> channels() const override {
        const std::uint64_t joints = scene_ ? scene_->world.joint_count : 0;
        const std::uint64_t chains = scene_ ? scene_->world.chains.size() : 0;
        return {{std::string(kChainPositionsChannel), sizeof(glm::vec3), joints, false},
                {std::string(kChainOrientationsChannel), sizeof(glm::quat), joints, false},
                {std::string(kChainRestChannel), sizeof(glm::vec3), joints, true},
                {std::string(kChainViewDirectionsChannel), sizeof(glm::vec3), chains, true},
                {std::string(kChainWeightsChannel), sizeof(float) * kChainWeights, chains, true}};
    }
    void keep_instances(InstanceRange range) override {
        if (!scene_ || (range.begin == 0 && range.end == scene_->instances.size())) return;
        scene_.emplace(scene_->slice(range.begin, range.end));
    }
    std::vector<std::string> outputs() const override { return {std::string(kChainDomain)}; }
    // The state an application draws from; the inputs are written for the step.
    std::vector<std::string> buffers() const override {
        if (!scene_) return {};
        return {std::string(rod_buffers::chain_states), std::string(rod_buffers::motion), std::string(rod_buffers::spin)};
    }
    Result<VulkanBufferRange> buffer(std::string_view name) const override {
        const DeviceData* data = device_data();
        if (data == nullptr) {
            return make_error(Error::Kind::InvalidInput, "domain \"chains\": \"" + std::string(name) +
                                                             "\" is not on a Vulkan device (a cpu backend, or no chains in this shard)");
        }
        return vulkan_buffer(*data, name);
    }

    Result<void> open(const DomainSetup& setup, std::span<Domain* const>) override {
        device_inputs_ = setup.device_inputs;
        // A shard may hold none of the characters: nothing to step then.
        if (!scene_ || scene_->instances.empty()) return {};
        const rods::LodSettings& lod = scene_->world.lod;
        if (lod.enabled && lod.budget_ms > 0.0f) {
            auto budget = rods::LodBudget::create(lod.budget_ms, /*measured=*/false, lod.costs, "lod.budget_ms");
            if (!budget) return budget.error();
            KW_TRY(take_budget(std::move(budget).value(), "lod.budget_ms"));
        }
        auto made = make_rod_backend(setup.kind, setup.options);
        if (!made) return made.error();
        rods_ = std::move(made).value();
        // Rigged characters' clips are evaluated by the pose backend of the same kind.
        auto created = CrowdAnimator::create(*scene_, setup.kind, setup.options);
        if (!created) return created.error();
        animator_.emplace(std::move(created).value());
        return {};
    }
    void close() override {
        animator_.reset();
        rods_.reset();
    }
    Result<void> rewind() override {
        host_input_frame_.reset();
        current_.reset();
        return {};
    }

    Result<void> step(std::uint32_t first, std::uint32_t frames, std::span<const ChannelOutput> out) override {
        if (!rods_) return {};
        for (std::uint32_t f = first; f < first + frames; ++f) {
            KW_TRY(frame(f));
            current_ = f;
            if (out.empty()) continue;
            // The channels asked for, from a snapshot read back after the frame.
            KW_TRY(rods_->read(snapshot_));
            for (const ChannelOutput& channel : out) {
                const std::span<const std::byte> from = snapshot_channel(snapshot_, channel.name);
                assert(channel.bytes.size() == std::size_t{frames} * from.size());
                std::memcpy(channel.bytes.data() + std::size_t{f - first} * from.size(), from.data(), from.size());
            }
        }
        return {};
    }

    // The frame's kinematic input made on the host (rigged characters' clips evaluated
    // in the pose backends' own submissions, waited for) and uploaded through the rod
    // backend's ring of frames in flight, then the step recorded (record_step). Frame 0
    // loads the world, submitting to the queue and waiting, and records nothing.
    Result<void> record(std::uint32_t f, compute::Recording& recording) override {
        if (!rods_) return {};
        if (animator_->writes_inputs_on_device()) {
            // The pose backends would overwrite the matrices that frames still in flight
            // read on the device.
            return make_error(Error::Kind::Unsupported,
                              "domain \"chains\": since step() the rigged characters' rod input is written on the device "
                              "from poses that each frame overwrites; record from frame 0, or make the Simulation with "
                              "SimulationOptions::device_inputs = false");
        }
        KW_TRY(frame(f, &recording));
        current_ = f;
        return {};
    }

    std::string device() const override { return rods_ ? rods_->device() : std::string(); }
    const DeviceData* device_data() const { return rods_ ? rods_->device_data() : nullptr; }
    std::uint32_t validation_messages() const override {
        std::uint32_t n = rods_ ? rods_->validation_messages() : 0;
        if (animator_) n = std::max(n, animator_->validation_messages());
        return n;
    }

    Result<void> show_on(render::Renderer& renderer, bool) override {
        KW_TRY(show_chains(renderer, rods_ ? &scene_->world : nullptr));
        return show_skinned(renderer, rods_ ? &*scene_ : nullptr);
    }

    Result<void> draw_on(render::Renderer& renderer, DrawSource source, bool) override {
        if (!rods_) return {};
        if (source == DrawSource::Device) {
            // The renderer reads back and uploads what is not on its device.
            KW_TRY(draw_chains(renderer, *rods_));
            KW_TRY(draw_skinned(renderer, *animator_, *rods_, current_.value_or(0)));
        } else {
            KW_TRY(rods_->read(snapshot_));
            KW_TRY(draw_chains(renderer, snapshot_));
            KW_TRY(draw_skinned(renderer, snapshot_, current_.value_or(0)));
        }
        return draw_colliders(renderer, *rods_, input_);
    }

    const RodScene* scene() const { return scene_ ? &*scene_ : nullptr; }
    Result<void> read(ChainSnapshot& out) {
        if (!rods_) return {};
        return rods_->read(out);
    }
    Result<void> read_levels(std::vector<rods::Level>& out, std::vector<std::uint8_t>* kept) {
        out.clear();
        if (kept) kept->clear();
        if (!rods_) return {};
        KW_TRY(rods_->read_states(states_));
        out.reserve(states_.size());
        for (const rods::ChainState& s : states_) out.push_back(static_cast<rods::Level>(s.level));
        if (kept) {
            // ChainState::idle counts the frames kept since the last step: 0 after a step.
            kept->reserve(states_.size());
            for (const rods::ChainState& s : states_) kept->push_back(s.idle > 0 ? 1 : 0);
        }
        return {};
    }
    const rods::RodFrame& input() const { return input_; }
    Result<const rods::RodFrame*> host_input() {
        if (!animator_ || !animator_->writes_inputs_on_device() || !current_) return &input_;
        if (host_input_frame_ != current_) {
            KW_TRY(animator_->host_frame(*current_, host_input_));
            host_input_.camera = input_.camera;
            host_input_frame_ = current_;
        }
        return &host_input_;
    }
    bool inputs_on_device() const { return animator_ && animator_->writes_inputs_on_device(); }
    void set_view_camera(std::optional<rods::Camera> camera) { view_camera_ = camera; }
    Result<void> set_wind(std::optional<rods::WindField> wind) {
        if (wind) KW_TRY(rods::validate(*wind, "set_wind: wind"));
        wind_ = wind;
        return {};
    }
    const ChainTiming& timing() const { return timing_; }

    Result<void> set_budget(float budget_ms, bool measured) {
        const rods::LodSettings& lod = scene_->world.lod;
        if (!lod.enabled) {
            return make_error(Error::Kind::InvalidInput,
                              "set_lod_budget: the scene's levels of detail are off (its `lod.enabled`, Scene::lod.enabled)");
        }
        auto budget = rods::LodBudget::create(budget_ms, measured, lod.costs, "set_lod_budget: budget_ms");
        if (!budget) return budget.error();
        return take_budget(std::move(budget).value(), "set_lod_budget");
    }
    const std::optional<rods::LodBudget>& budget() const { return budget_; }

private:
    // The budget ranks characters by their reference joints on the host: the rigged
    // characters' rod input stays there (their reference joints are what the pose
    // backends write on the device otherwise).
    Result<void> take_budget(rods::LodBudget budget, const char* what) {
        // A shard would rank its own characters alone and spend the whole budget on them:
        // its chains would not be the whole run's.
        if (scene_->instances.size() != scene_characters_) {
            return make_error(Error::Kind::Unsupported,
                              std::string(what) + ": a budget ranks every character of the scene, and this shard holds " +
                                  std::to_string(scene_->instances.size()) + " of its " + std::to_string(scene_characters_) +
                                  "; bake the shards without a budget, or the scene whole");
        }
        if (animator_ && animator_->writes_inputs_on_device()) {
            return make_error(Error::Kind::Unsupported,
                              std::string(what) + ": the rigged characters' rod input is written on the device since the first "
                              "step; set the budget before it, or make the Simulation with SimulationOptions::device_inputs = false");
        }
        device_inputs_ = false;
        chains_per_character_.assign(scene_->world.character_count, 0);
        for (const rods::ChainInstance& chain : scene_->world.chains) ++chains_per_character_[chain.character];
        budget_ = std::move(budget);
        return {};
    }

    // Frame `f` of the chains: the kinematic input, then the initial state (f == 0) or one
    // step, submitted, or recorded into `recording` when one is given (record()).
    Result<void> frame(std::uint32_t f, compute::Recording* recording = nullptr) {
        KW_TRY(animator_->frame(f, input_));
        const double pose_ms = animator_->last_pose_ms();
        timing_.pose_ms += pose_ms;
        if (view_camera_) input_.camera = *view_camera_;
        if (wind_ && !input_.winds.empty()) input_.winds[0] = *wind_;
        if (budget_) {
            references_.resize(input_.reference.size());
            for (std::size_t c = 0; c < references_.size(); ++c) references_[c] = input_.reference[c].position;
            input_.full_distance_cap = budget_->cap(rods::lod_view(scene_->world.lod, input_.camera), references_, chains_per_character_);
        }
        const auto start = std::chrono::steady_clock::now();
        if (f == 0) {
            KW_TRY(rods_->load(scene_->world, input_));
        } else {
            if (recording != nullptr) {
                auto* device = dynamic_cast<DeviceRodBackend*>(rods_.get());
                if (device == nullptr) {
                    return make_error(Error::Kind::Unsupported, "domain \"chains\" records into a command buffer on the vulkan backend only");
                }
                KW_TRY(device->record_external(*recording, input_));
            } else {
                KW_TRY(rods_->step(input_));
            }
        }
        if (f == 0 && device_inputs_ && recording == nullptr) {
            // From now on the rigged characters' input is written where the chains step
            // (when the pose and rod backends share a Vulkan device; nothing otherwise).
            // Not when recording: frames in flight would read the pose matrices the next
            // frame's clips overwrite.
            auto took = animator_->write_inputs_on(*rods_);
            if (!took) return took.error();
        }
        const double step_seconds = seconds_since(start);
        (f < 2 ? timing_.warmup_seconds : timing_.seconds) += step_seconds;
        // A measured budget learns this machine's cost of the frame it priced (clips and
        // chains; a recorded step's time is the application's to measure).
        if (budget_ && f > 0 && recording == nullptr) budget_->observe(pose_ms + step_seconds * 1000.0);
        if (f >= 2 && recording == nullptr && rods_->last_gpu_ms() >= 0.0) timing_.gpu_ms += rods_->last_gpu_ms();
        return {};
    }

    std::optional<RodScene> scene_;
    std::uint32_t scene_characters_;  // before keep_instances()
    bool device_inputs_ = true;
    std::unique_ptr<RodBackend> rods_;
    std::optional<CrowdAnimator> animator_;
    std::optional<rods::Camera> view_camera_;
    std::optional<rods::WindField> wind_;  // set_wind(): the scene's field from now on
    std::optional<rods::LodBudget> budget_;  // the scene's lod.budget_ms, or set_lod_budget()
    std::vector<std::uint32_t> chains_per_character_;
    std::vector<glm::vec3> references_;
    rods::RodFrame input_;
    rods::RodFrame host_input_;
    std::optional<std::uint32_t> host_input_frame_;
    std::optional<std::uint32_t> current_;
    ChainSnapshot snapshot_;  // DrawSource::ReadBack
    std::vector<rods::ChainState> states_;  // read_levels()
    ChainTiming timing_;
};

ChainDomain* find(const Simulation& sim) { return dynamic_cast<ChainDomain*>(sim.domain(kChainDomain)); }

}  // namespace

std::unique_ptr<Domain> make_chain_domain(std::optional<RodScene> scene) {
    return std::make_unique<ChainDomain>(std::move(scene));
}

const RodScene* rod_scene_of(const Domain& domain) {
    const auto* chains = dynamic_cast<const ChainDomain*>(&domain);
    return chains ? chains->scene() : nullptr;
}

const RodScene* rod_scene(const Simulation& sim) {
    const ChainDomain* domain = find(sim);
    return domain ? domain->scene() : nullptr;
}

Result<void> read_chains(Simulation& sim, ChainSnapshot& out) {
    ChainDomain* domain = find(sim);
    return domain ? domain->read(out) : Result<void>{};
}

Result<void> read_chain_levels(Simulation& sim, std::vector<rods::Level>& out, std::vector<std::uint8_t>* kept) {
    ChainDomain* domain = find(sim);
    if (domain == nullptr) {
        out.clear();
        if (kept) kept->clear();
        return {};
    }
    return domain->read_levels(out, kept);
}

const rods::RodFrame& chain_input(const Simulation& sim) {
    static const rods::RodFrame none;
    const ChainDomain* domain = find(sim);
    return domain ? domain->input() : none;
}

Result<const rods::RodFrame*> host_chain_input(Simulation& sim) {
    static const rods::RodFrame none;
    ChainDomain* domain = find(sim);
    return domain ? domain->host_input() : Result<const rods::RodFrame*>{&none};
}

bool rod_inputs_on_device(const Simulation& sim) {
    const ChainDomain* domain = find(sim);
    return domain && domain->inputs_on_device();
}

void set_view_camera(Simulation& sim, std::optional<rods::Camera> camera) {
    if (ChainDomain* domain = find(sim)) domain->set_view_camera(camera);
}

Result<void> set_wind(Simulation& sim, std::optional<rods::WindField> wind) {
    if (ChainDomain* domain = find(sim)) return domain->set_wind(wind);
    return {};
}

Result<void> set_lod_budget(Simulation& sim, float budget_ms, bool measured) {
    ChainDomain* domain = find(sim);
    if (domain == nullptr || domain->scene() == nullptr) {
        return make_error(Error::Kind::InvalidInput, "set_lod_budget: the simulation has no characters' chains");
    }
    return domain->set_budget(budget_ms, measured);
}

std::optional<LodBudgetState> lod_budget(const Simulation& sim) {
    const ChainDomain* domain = find(sim);
    if (domain == nullptr || !domain->budget()) return std::nullopt;
    const rods::LodBudget& b = *domain->budget();
    return LodBudgetState{b.budget_ms(), b.measured(), b.scale(), domain->input().full_distance_cap, b.modelled_ms()};
}

const ChainTiming& chain_timing(const Simulation& sim) {
    static const ChainTiming none;
    const ChainDomain* domain = find(sim);
    return domain ? domain->timing() : none;
}

}  // namespace kodawari
