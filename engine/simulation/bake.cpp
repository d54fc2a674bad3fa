// The bake loop (kodawari/bake.hpp): one frame order for every output, so that `run`,
// `merge`, a distributed bake and embedders write the same bytes.
#include "kodawari/bake.hpp"

#include <algorithm>
#include <string>

#include "kodawari/backend.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/simulation.hpp"

namespace kodawari {

namespace {

// Bird poses read back per step when birds go in chunks: bounds the chunk buffers
// (2^18 x 128 bytes = 32 MiB of poses, as much of diagnostics) while amortizing the
// step calls.
constexpr std::size_t kChunkPoses = std::size_t{1} << 18;

// A Simulation's frames, read back into buffers reused from chunk to chunk.
class SimulationSource final : public BakeSource {
public:
    explicit SimulationSource(Simulation& sim) : sim_(sim) {}

    BakeWorld world() const override {
        return {&sim_.scene(), &bird_world(sim_), rod_scene(sim_), sim_.frame_count(),
                std::string(backend_name(sim_.backend()))};
    }

    std::uint32_t chunk_frames() const override {
        // The whole scene's birds, so that a shard steps in the chunks of the whole.
        return bake_chunk_frames(sim_.shard().part("birds").scene_count, rod_scene(sim_) != nullptr);
    }

    Result<BakeFrames> next(std::uint32_t first, std::uint32_t count, const BakeNeeds& needs) override {
        const std::size_t birds = bird_world(sim_).birds.size();
        std::span<gpu::BirdPose> poses;
        std::span<gpu::BirdDiag> diag;
        if (birds > 0 && (needs.bird_poses || needs.bird_diag)) {
            // Diagnostics come with the poses they describe.
            poses_.resize(std::size_t{count} * birds);
            poses = poses_;
            if (needs.bird_diag) {
                diag_.resize(std::size_t{count} * birds);
                diag = diag_;
            }
        }
        KW_TRY(step_birds(sim_, count, poses, diag));
        const bool chains = needs.chains && rod_scene(sim_) != nullptr;
        if (chains) KW_TRY(read_chains(sim_, snapshot_));
        return BakeFrames{first, count, poses, diag, chains ? &snapshot_ : nullptr};
    }

private:
    Simulation& sim_;
    std::vector<gpu::BirdPose> poses_;
    std::vector<gpu::BirdDiag> diag_;
    ChainSnapshot snapshot_;
};

}  // namespace

std::uint32_t bake_chunk_frames(std::size_t scene_birds, bool has_chains) {
    if (has_chains) return 1;
    return static_cast<std::uint32_t>(std::clamp<std::size_t>(kChunkPoses / std::max<std::size_t>(scene_birds, 1), 1, 120));
}

Result<std::vector<BakeOutput>> bake(BakeSource& source, std::span<BakeSink* const> sinks, const BakeOptions& options) {
    const BakeWorld world = source.world();
    BakeNeeds needs;
    for (BakeSink* sink : sinks) {
        const BakeNeeds n = sink->needs();
        needs.bird_poses |= n.bird_poses;
        needs.bird_diag |= n.bird_diag;
        needs.chains |= n.chains;
        needs.chain_shapes |= n.chain_shapes;
    }
    for (BakeSink* sink : sinks) KW_TRY(sink->begin(world));
    const std::uint32_t chunk = source.chunk_frames();
    for (std::uint32_t done = 0; done < world.frames;) {
        const std::uint32_t n = std::min(chunk, world.frames - done);
        auto frames = source.next(done, n, needs);
        if (!frames) return frames.error();
        for (BakeSink* sink : sinks) KW_TRY(sink->consume(frames.value()));
        done += n;
        if (options.progress) options.progress(done, world.frames);
    }
    if (options.simulated) KW_TRY(options.simulated());
    std::vector<BakeOutput> written;
    for (BakeSink* sink : sinks) {
        auto files = sink->finish();
        if (!files) return files.error();
        for (BakeOutput& file : files.value()) written.push_back(std::move(file));
    }
    return written;
}

Result<std::vector<BakeOutput>> bake(Simulation& sim, std::span<BakeSink* const> sinks, const BakeOptions& options) {
    if (sim.frame()) {
        return make_error(Error::Kind::InvalidInput, sim.scene().path + ": bake needs a simulation that has not stepped yet");
    }
    SimulationSource source(sim);
    return bake(source, sinks, options);
}

std::unique_ptr<BakeSource> make_simulation_source(Simulation& sim) { return std::make_unique<SimulationSource>(sim); }

}  // namespace kodawari
