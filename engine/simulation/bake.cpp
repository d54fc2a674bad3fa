// The bake loop (kodawari/simulation/bake.hpp): one frame order for every output, so that `run`,
// `merge`, a distributed bake and embedders write the same bytes. It moves channels
// (kodawari/simulation/domain.hpp) and names no domain.
#include "kodawari/simulation/bake.hpp"

#include <algorithm>
#include <string>

#include "kodawari/backends/backend.hpp"
#include "kodawari/simulation/simulation.hpp"

namespace kodawari {

namespace {

// A Simulation's frames, read back into buffers reused from chunk to chunk.
class SimulationSource final : public BakeSource {
public:
    explicit SimulationSource(Simulation& sim) : sim_(sim) {}

    BakeWorld world() const override {
        BakeWorld world{&sim_.scene(), {}, sim_.frame_count(), std::string(backend_name(sim_.backend()))};
        for (const Domain* domain : sim_.domains()) world.domains.push_back(domain);
        return world;
    }

    std::uint32_t chunk_frames() const override {
        // Domains answer from the whole scene's instances, so that a shard steps in the
        // chunks of the whole.
        std::vector<const Domain*> domains(sim_.domains().begin(), sim_.domains().end());
        return bake_chunk_frames(domains);
    }

    Result<BakeFrames> next(std::uint32_t first, std::uint32_t count, const BakeNeeds& needs) override {
        std::vector<ChannelOutput> out;
        BakeFrames frames{first, count, {}};
        buffers_.resize(needs.channels.size());
        std::size_t used = 0;
        for (const std::string& name : needs.channels) {
            for (const ChannelInfo& info : sim_.channels()) {
                if (info.name != name) continue;
                std::vector<std::byte>& buffer = buffers_[used++];
                buffer.resize(std::size_t{count} * info.elements * info.element_bytes);
                out.push_back({name, buffer});  // `needs` outlives the step
            }
        }
        KW_TRY(sim_.step(count, out));
        for (const ChannelOutput& o : out) frames.channels.push_back({std::string(o.name), o.bytes});
        return frames;
    }

private:
    Simulation& sim_;
    std::vector<std::vector<std::byte>> buffers_;
};

}  // namespace

const Domain* BakeWorld::domain(std::string_view name) const {
    for (const Domain* d : domains) {
        if (d->name() == name) return d;
    }
    return nullptr;
}

std::optional<ChannelInfo> BakeWorld::channel(std::string_view name) const {
    for (const Domain* d : domains) {
        for (ChannelInfo& info : d->channels()) {
            if (info.name == name) return std::move(info);
        }
    }
    return std::nullopt;
}

Result<void> BakeSink::share(const ShardInfo&) {
    return make_error(Error::Kind::Internal, "this bake sink cannot share its work between ranks");
}

Result<std::vector<BakeOutput>> BakeSink::finish_shared(Communicator&) {
    return make_error(Error::Kind::Internal, "this bake sink cannot share its work between ranks");
}

std::span<const std::byte> BakeFrames::channel(std::string_view name) const {
    for (const BakeChannel& c : channels) {
        if (c.name == name) return c.bytes;
    }
    return {};
}

std::uint32_t bake_chunk_frames(std::span<const Domain* const> domains) {
    std::uint32_t frames = kMaxBakeFrames;
    for (const Domain* domain : domains) frames = std::min(frames, std::max(domain->max_bake_frames(), 1u));
    return frames;
}

Result<std::vector<BakeOutput>> bake(BakeSource& source, std::span<BakeSink* const> sinks, const BakeOptions& options) {
    const BakeWorld world = source.world();
    BakeNeeds needs;
    for (BakeSink* sink : sinks) {
        for (std::string& name : sink->needs().channels) {
            if (std::find(needs.channels.begin(), needs.channels.end(), name) == needs.channels.end()) {
                needs.channels.push_back(std::move(name));
            }
        }
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
