// The bake loop (kodawari/bake.hpp): one frame order for every output, so that `run`
// and embedders write the same bytes.
#include "kodawari/bake.hpp"

#include <algorithm>
#include <string>

#include "kodawari/backend.hpp"
#include "kodawari/simulation.hpp"

namespace kodawari {

namespace {
// Bird poses read back per step when birds go in chunks: bounds the chunk buffers
// (2^18 x 128 bytes = 32 MiB of poses, as much of diagnostics) while amortizing the
// step calls.
constexpr std::size_t kChunkPoses = std::size_t{1} << 18;
}  // namespace

Result<std::vector<BakeOutput>> bake(Simulation& sim, std::span<BakeSink* const> sinks, const BakeOptions& options) {
    if (sim.frame()) {
        return make_error(Error::Kind::InvalidInput, sim.scene().path + ": bake needs a simulation that has not stepped yet");
    }
    const std::uint32_t frames = sim.frame_count();
    BakeNeeds needs;
    for (BakeSink* sink : sinks) {
        const BakeNeeds n = sink->needs();
        needs.bird_poses |= n.bird_poses;
        needs.bird_diag |= n.bird_diag;
        needs.chains |= n.chains;
    }
    const BakeWorld world{&sim.scene(), &sim.bird_world(), sim.rod_scene(), frames, std::string(backend_name(sim.backend()))};
    for (BakeSink* sink : sinks) KW_TRY(sink->begin(world));

    const std::size_t count = sim.bird_world().birds.size();
    const bool birds_read = count > 0 && (needs.bird_poses || needs.bird_diag);
    const bool chains_read = needs.chains && sim.rod_scene() != nullptr;
    // Chains are read back after every frame; birds alone go several frames per step.
    const std::uint32_t chunk =
        sim.rod_scene() != nullptr
            ? 1u
            : static_cast<std::uint32_t>(std::clamp<std::size_t>(kChunkPoses / std::max<std::size_t>(count, 1), 1, 120));
    std::vector<gpu::BirdPose> poses;
    std::vector<gpu::BirdDiag> diag;
    ChainSnapshot snapshot;
    for (std::uint32_t done = 0; done < frames;) {
        const std::uint32_t n = std::min(chunk, frames - done);
        StepOutput out;
        if (birds_read) {
            // Diagnostics come with the poses they describe.
            poses.resize(std::size_t{n} * count);
            out.bird_poses = poses;
            if (needs.bird_diag) {
                diag.resize(std::size_t{n} * count);
                out.bird_diag = diag;
            }
        }
        KW_TRY(sim.step(n, out));
        if (chains_read) KW_TRY(sim.read_chains(snapshot));
        const BakeFrames handed{done, n, out.bird_poses, out.bird_diag, chains_read ? &snapshot : nullptr};
        for (BakeSink* sink : sinks) KW_TRY(sink->consume(handed));
        done += n;
        if (options.progress) options.progress(done, frames);
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

}  // namespace kodawari
