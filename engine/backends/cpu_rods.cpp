// The cpu-reference rod backend: engine/rods (world.cpp, solver.cpp) chain after chain on
// one thread, the validation oracle. (The cpu backend is simd_rods.cpp.)
#include <algorithm>
#include <string>
#include <vector>

#include "backends/backends.hpp"

namespace kodawari {

bool step_chain_reference(const rods::RodWorld& world, std::uint32_t chain, const rods::RodFrame& frame,
                          rods::ChainState& state, rods::KeyState& keys, rods::RestShape* rest_out) {
    const rods::ChainInstance& c = world.chains[chain];
    const rods::ChainTemplate& t = world.templ(c);
    // The center is followed every frame (a chain with one never rests).
    if (c.center != rods::kNoCenter) {
        rods::follow_center(state.center, frame.centers[c.center], state);
        state.center = frame.centers[c.center];
    }
    // Its level of detail this frame (rods::chain_level, from its character's reference joint).
    // A frame whose camera gives no levels (LOD off, an orthographic camera) has every chain
    // full at once.
    const rods::LodView view = rods::lod_view(world.lod, frame.camera, frame.full_distance_cap);
    const glm::vec3 reference = frame.reference[c.character].position;
    const rods::Level previous = static_cast<rods::Level>(state.level);
    const rods::Level level = rods::chain_level(view, reference, previous);
    // The posed and hidden levels' rate: between its turns a chain keeps its state.
    if (frame.number != rods::kNoFrameNumber &&
        rods::chain_rests(view, reference, level, previous, rods::rate_turn(frame.number, frame.first_character + c.character))) {
        ++state.idle;
        return false;
    }
    // Its keys over the frames since its last step (their motion measured across them, as
    // its clip's pose renews at its turns).
    const rods::KeyedWeights keyed = rods::measure_keys(world, chain, frame, keys, state.idle + 1);
    // A posed step covers the frames the chain kept too (its root's motion over them is
    // the carry; the ease and the velocities take their length).
    const float posed_dt = frame.dt * static_cast<float>(state.idle + 1);
    state.idle = 0;
    rods::RestShape rest = rods::rest_shape(world, chain, frame, keyed);
    state.level = static_cast<std::uint32_t>(level);
    const float share = view.enabled ? rods::blend_in(world.lod, level, state.blend_in, frame.dt) : 1.0f;
    state.blend_in = share;
    const std::span<const rods::Collider> colliders(frame.colliders.data() + c.collider_begin, c.collider_count);
    const rods::Transform& root = frame.roots[chain];
    // A reduced chain steps as a full one at half the substeps and iterations.
    rods::SolverParams reduced;
    const rods::SolverParams& params = level == rods::Level::Reduced ? (reduced = rods::reduced_params(t.params)) : t.params;
    if (!rods::dynamic(level)) {
        rods::step_posed(t.chain, t.params, root, rest.shape, colliders, posed_dt, rods::posed_blend(world.lod, posed_dt),
                         state);
    } else if (share < 1.0f) {
        // Turning full (or reduced) again: the step and the posed frame from the same start (the
        // teleport's carry and the first step's start done here, once, as the other
        // backends do them before their kernels; step() and step_posed() then find neither
        // left to do), mixed.
        rods::follow_teleport(params, root, frame.dt, state);
        if (!state.started && params.settle_start) rods::start_moving(root, frame.dt, state);
        state.started = true;
        const rods::ChainState before = state;
        rods::ChainState posed = state;
        rods::step_posed(t.chain, t.params, root, rest.shape, colliders, frame.dt, rods::posed_blend(world.lod, frame.dt),
                         posed);
        rods::step(t.chain, params, root, rest.shape, colliders, frame.dt, state, rods::chain_air(world, chain, frame));
        rods::hand_over(t.chain, before, posed, share, frame.dt, state);
    } else {
        rods::step(t.chain, params, root, rest.shape, colliders, frame.dt, state, rods::chain_air(world, chain, frame));
    }
    if (rest_out != nullptr) *rest_out = std::move(rest);
    return true;
}

namespace {

constexpr std::size_t kWeights = rods::kMaxViewExamples + 1;

class CpuRodBackend final : public RodBackend {
public:
    std::string_view name() const override { return "cpu-reference"; }
    std::string device() const override { return "1 thread"; }

    Result<void> load(const rods::RodWorld& world, const rods::RodFrame& initial) override {
        KW_TRY(rods::check_frame(world, initial));
        world_ = &world;
        const std::size_t count = world.chains.size();
        states_.resize(count);
        keys_.resize(count);
        view_.assign(count, glm::vec3(0.0f));
        weights_.assign(count * kWeights, 0.0f);
        rest_.assign(world.joint_count, glm::vec3(0.0f));
        run([&](std::uint32_t c) {
            const rods::RestShape rest = rods::rest_shape(world, c, initial);
            states_[c] = rods::initial_chain_state(world, c, initial);
            keys_[c] = rods::initial_key_state(world, c, initial);
            keep(c, rest);
        });
        return {};
    }

    Result<void> step(const rods::RodFrame& frame) override {
        assert(world_ != nullptr && "load() first");
        KW_TRY(rods::check_frame(*world_, frame));
        run([&](std::uint32_t c) {
            rods::RestShape rest;
            if (step_chain_reference(*world_, c, frame, states_[c], keys_[c], &rest)) keep(c, rest);
        });
        return {};
    }

    Result<void> read(ChainSnapshot& out) override {
        assert(world_ != nullptr && "load() first");
        out.positions.resize(world_->joint_count);
        out.orientations.resize(world_->joint_count);
        out.rest = rest_;
        out.view_directions = view_;
        out.weights = weights_;
        for (std::size_t c = 0; c < world_->chains.size(); ++c) {
            const rods::ChainInstance& chain = world_->chains[c];
            const std::uint32_t n = world_->templ(chain).chain.joint_count;
            for (std::uint32_t i = 0; i < n; ++i) {
                out.positions[chain.joint_begin + i] = rods::position(states_[c], i);
                out.orientations[chain.joint_begin + i] = states_[c].q[i];
            }
        }
        return {};
    }

    Result<void> read_states(std::vector<rods::ChainState>& out) override {
        out = states_;
        return {};
    }

private:
    template <typename Fn>
    void run(Fn&& fn) {
        for (std::size_t c = 0; c < world_->chains.size(); ++c) fn(static_cast<std::uint32_t>(c));
    }

    // What read() reports besides the state: the frame's view, weights and rest shape.
    void keep(std::uint32_t c, const rods::RestShape& rest) {
        const rods::ChainInstance& chain = world_->chains[c];
        view_[c] = rest.view_direction;
        std::copy(rest.weights.begin(), rest.weights.end(), weights_.begin() + static_cast<std::ptrdiff_t>(c * kWeights));
        const rods::Transform& root = states_[c].root;
        for (std::size_t i = 0; i < rest.shape.positions.size(); ++i) {
            rest_[chain.joint_begin + i] = root.position + root.rotation * rest.shape.positions[i];
        }
    }

    const rods::RodWorld* world_ = nullptr;
    std::vector<rods::ChainState> states_;
    std::vector<rods::KeyState> keys_;
    std::vector<glm::vec3> view_;
    std::vector<float> weights_;
    std::vector<glm::vec3> rest_;
};

}  // namespace

std::unique_ptr<RodBackend> new_reference_rod_backend() { return std::make_unique<CpuRodBackend>(); }

}  // namespace kodawari
