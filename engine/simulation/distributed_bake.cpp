// A bake over the ranks of a job (kodawari/simulation/distributed.hpp). Every step is collective and
// followed by agree(), so that a failure anywhere ends every rank at the same point
// instead of leaving the others waiting in a gather.
#include "kodawari/simulation/distributed.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>

#include <unistd.h>

#include "kodawari/vulkan/gpu_info.hpp"
#include "kodawari/scene/scene.hpp"
#include "simulation/frame_payload.hpp"
#include "simulation/scene_worlds.hpp"

namespace kodawari {

namespace {

// The ranks on one machine take different devices when it has several of the kind the
// engine would pick (never a CPU device beside a GPU).
void choose_device_by_local_rank(SimulationOptions& options, int local_rank) {
    if (!options.options.device.empty() || options.options.context) return;
    if (options.backend && *options.backend != BackendKind::Vulkan) return;
    auto gpus = list_gpus("");
    if (!gpus || gpus.value().chosen < 0) return;
    const GpuInventory& inventory = gpus.value();
    const std::string& type = inventory.devices[static_cast<std::size_t>(inventory.chosen)].type;
    std::vector<std::uint32_t> candidates;
    for (const GpuDeviceInfo& d : inventory.devices) {
        if (d.rejected.empty() && d.type == type) candidates.push_back(d.index);
    }
    if (candidates.size() < 2) return;
    options.options.device = std::to_string(candidates[static_cast<std::size_t>(local_rank) % candidates.size()]);
}

std::vector<std::byte> bytes_of(const void* data, std::size_t size) {
    std::vector<std::byte> out(size);
    if (size != 0) std::memcpy(out.data(), data, size);  // memcpy of null, even for 0 bytes, is undefined
    return out;
}

// Rank 0's lines (none may hold a newline), on every rank.
std::vector<std::string> broadcast_lines(Communicator& comm, const std::vector<std::string>& lines) {
    std::string text;
    for (const std::string& line : lines) text += line + "\n";
    std::vector<std::byte> bytes = bytes_of(text.data(), text.size());
    comm.broadcast(bytes);
    std::vector<std::string> out(1);
    for (const std::byte b : bytes) {
        if (static_cast<char>(b) == '\n') {
            out.emplace_back();
        } else {
            out.back().push_back(static_cast<char>(b));
        }
    }
    out.pop_back();  // after the last newline: nothing
    return out;
}

// The ranks write a shared sink's file where rank 0 made it: only where every rank sees
// that folder as rank 0 does (a file system they share, the same working directory for
// a relative path). Rank 0 puts a probe file there and asks; a sink some rank cannot
// see is not shared, and rank 0 writes it from the gathered frames, as any other sink.
// Checked before the first frame, so that a farm without a shared file system loses
// no bake. Collective; `shared` is rank 0's (changed there only).
// Returns, per sink, why it is not shared after all ("" where it is or never could be).
std::vector<std::string> share_where_every_rank_sees(Communicator& comm, const std::vector<std::unique_ptr<BakeSink>>& sinks,
                                                     std::vector<std::byte>& shared) {
    const bool root = comm.rank() == 0;
    std::vector<std::string> probes;  // per sink: its probe's path, or nothing
    std::vector<std::string> made;
    if (root) {
        for (std::size_t k = 0; k < sinks.size(); ++k) {
            std::string probe;
            if (shared[k] != std::byte{0}) {
                const std::filesystem::path out = sinks[k]->share_probe();
                probe = (out.parent_path() / (out.filename().string() + ".probe-" + std::to_string(::getpid()) + "-" +
                                              std::to_string(k)))
                            .string();
                std::FILE* file = out.empty() ? nullptr : std::fopen(probe.c_str(), "wb");
                if (file == nullptr) {
                    probe.clear();  // rank 0 cannot write there either: its own sink will say so
                    shared[k] = std::byte{0};
                } else {
                    std::fclose(file);
                    made.push_back(probe);
                }
            }
            probes.push_back(probe);
        }
    }
    std::vector<std::byte> seen;  // per sink: 1 where this rank can write its probe
    for (const std::string& probe : broadcast_lines(comm, probes)) {
        seen.push_back(std::byte{static_cast<unsigned char>(!probe.empty() && ::access(probe.c_str(), W_OK) == 0)});
    }
    std::vector<std::byte> all;
    std::vector<std::size_t> sizes;
    comm.gather(seen, all, sizes);
    std::vector<std::string> why(sinks.size());
    if (!root) return why;
    for (const std::string& probe : made) std::remove(probe.c_str());
    // Every rank's answers, rank after rank, one per sink.
    for (std::size_t at = 0; at < all.size(); ++at) {
        const std::size_t k = at % shared.size();
        if (all[at] != std::byte{0} || shared[k] == std::byte{0}) continue;
        shared[k] = std::byte{0};
        why[k] = "written by rank 0 alone: rank " + std::to_string(at / shared.size()) +
                 " cannot write into its folder (not a file system every rank shares)";
    }
    return why;
}

}  // namespace

Result<std::vector<BakeOutput>> bake_distributed(Communicator& comm, const std::string& scene_path,
                                                 const DistributedBakeOptions& options) {
    const bool root = comm.rank() == 0;
    SimulationOptions sim_options = options.simulation;
    sim_options.shard = {static_cast<std::uint32_t>(comm.rank()), static_cast<std::uint32_t>(comm.size())};
    choose_device_by_local_rank(sim_options, comm.local_rank());
    auto opened = [&]() -> Result<std::unique_ptr<Simulation>> {
        if (!options.prepare_scene) return Simulation::open(scene_path, sim_options);
        auto scene = load_scene(scene_path);
        if (!scene) return scene.error();
        if (auto prepared = options.prepare_scene(scene.value()); !prepared) return prepared.error();
        return Simulation::create(std::move(scene).value(), sim_options);
    }();
    KW_TRY(comm.agree(opened ? Result<void>{} : Result<void>{opened.error()}));
    Simulation& sim = *opened.value();
    if (options.opened) options.opened(sim);

    // Rank 0: the whole scene's world (built, not simulated) and the sinks.
    std::optional<detail::SceneWorlds> worlds;
    std::vector<std::unique_ptr<BakeSink>> sinks;
    const auto build_world = [&]() -> Result<BakeWorld> {
        auto built = detail::build_scene_worlds(sim.scene(), sim.frame_count());
        if (!built) return built.error();
        worlds.emplace(std::move(built).value());
        return worlds->bake_world(sim.scene(), std::string(backend_name(sim.backend())));
    };
    Result<void> setup;
    if (root) {
        auto world = build_world();
        if (world) {
            sinks = options.make_sinks(world.value());
            for (const auto& sink : sinks) {
                setup = sink->begin(world.value());
                if (!setup) break;
            }
        } else {
            setup = world.error();
        }
    }
    KW_TRY(comm.agree(setup));

    // Which sinks every rank shares (BakeSink::can_share(), rank 0's answer): the other
    // ranks make the same sinks on the whole scene's world and begin those, and every
    // rank tells them its shard. The others' frames go to rank 0 alone.
    std::vector<std::byte> shared(sinks.size());
    for (std::size_t k = 0; k < sinks.size(); ++k) shared[k] = std::byte{static_cast<unsigned char>(sinks[k]->can_share())};
    const std::vector<std::string> not_shared = share_where_every_rank_sees(comm, sinks, shared);
    comm.broadcast(shared);
    const auto is_shared = [&](std::size_t k) { return shared[k] != std::byte{0}; };
    bool any_shared = false;
    bool gathering = false;
    for (std::size_t k = 0; k < shared.size(); ++k) (is_shared(k) ? any_shared : gathering) = true;
    Result<void> joined;
    if (!root && any_shared) {
        joined = [&]() -> Result<void> {
            auto world = build_world();
            if (!world) return world.error();
            sinks = options.make_sinks(world.value());
            if (sinks.size() != shared.size()) {
                return make_error(Error::Kind::Internal, "make_sinks made " + std::to_string(sinks.size()) + " sinks here, " +
                                                             std::to_string(shared.size()) + " on rank 0");
            }
            for (std::size_t k = 0; k < sinks.size(); ++k) {
                if (!is_shared(k)) continue;
                KW_TRY(sinks[k]->begin(world.value()));
                if (!sinks[k]->can_share()) {
                    return make_error(Error::Kind::Internal, "sink " + std::to_string(k) + " cannot share its work here, as it can on rank 0");
                }
            }
            return {};
        }();
    }
    KW_TRY(comm.agree(joined));
    Result<void> sharing;
    for (std::size_t k = 0; k < shared.size() && sharing; ++k) {
        if (is_shared(k)) sharing = sinks[k]->share(sim.shard());
    }
    KW_TRY(comm.agree(sharing));

    // What every rank steps: every sink's channels (rank 0's needs, one name per line, to
    // all); of them, those of the sinks rank 0 alone feeds are gathered. Every rank's
    // elements per gathered channel go to rank 0. Every rank has the same domains, so
    // the same channels in the same order.
    const auto names_of = [&](bool of_shared) {
        BakeNeeds needs;
        for (std::size_t k = 0; k < sinks.size(); ++k) {
            if (of_shared && !is_shared(k)) continue;
            if (!of_shared && is_shared(k)) continue;
            for (std::string& name : sinks[k]->needs().channels) {
                if (std::find(needs.channels.begin(), needs.channels.end(), name) == needs.channels.end()) {
                    needs.channels.push_back(std::move(name));
                }
            }
        }
        return needs;
    };
    const auto broadcast_names = [&](const BakeNeeds& needs) { return BakeNeeds{broadcast_lines(comm, needs.channels)}; };
    const BakeNeeds gathered = broadcast_names(root ? names_of(false) : BakeNeeds{});
    BakeNeeds needs = gathered;
    for (std::string& name : broadcast_names(root ? names_of(true) : BakeNeeds{}).channels) {
        if (std::find(needs.channels.begin(), needs.channels.end(), name) == needs.channels.end()) {
            needs.channels.push_back(std::move(name));
        }
    }
    std::vector<const Domain*> mine(sim.domains().begin(), sim.domains().end());
    const detail::PayloadLayout content = detail::payload_layout(mine, gathered);
    std::vector<std::byte> all;
    std::vector<std::size_t> sizes;
    std::optional<detail::FrameAssembler> assembler;
    std::vector<std::string> names;
    if (gathering) {
        std::vector<std::uint64_t> elements;
        for (const ChannelInfo& c : content.channels) elements.push_back(c.elements);
        comm.gather(std::as_bytes(std::span(elements)), all, sizes);
        if (root) {
            std::vector<detail::PayloadLayout> layouts;
            std::size_t at = 0;
            for (int r = 0; r < comm.size(); ++r) {
                detail::PayloadLayout layout = content;
                for (ChannelInfo& c : layout.channels) {
                    std::memcpy(&c.elements, all.data() + at, sizeof c.elements);
                    at += sizeof c.elements;
                }
                layouts.push_back(std::move(layout));
                names.push_back("rank " + std::to_string(r));
            }
            assembler.emplace(std::move(layouts));
        }
    }

    auto source = make_simulation_source(sim);
    const std::uint32_t frames = sim.frame_count();
    const std::uint32_t chunk = source->chunk_frames();  // the whole scene's, the same on every rank
    std::vector<std::byte> payload;
    // Every rank hands its own frames to the shared sinks; rank 0 writes chunk k of the
    // others while they simulate chunk k + 1: each rank's status for chunk k joins the
    // agreement on chunk k + 1's steps (and the last one is agreed after the loop), so
    // that no rank waits for the writer before stepping on.
    Result<void> consumed;
    for (std::uint32_t done = 0; done < frames;) {
        const std::uint32_t n = std::min(chunk, frames - done);
        auto stepped = source->next(done, n, needs);
        KW_TRY(comm.agree(!consumed ? consumed : stepped ? Result<void>{} : Result<void>{stepped.error()}));
        for (std::size_t k = 0; k < sinks.size() && consumed; ++k) {
            if (is_shared(k)) consumed = sinks[k]->consume(stepped.value());
        }
        if (gathering) {
            detail::encode_frames(stepped.value(), content, payload);
            comm.gather(payload, all, sizes);
        }
        if (root && gathering && consumed) {
            std::vector<std::span<const std::byte>> parts;
            std::size_t at = 0;
            for (std::size_t size : sizes) {
                parts.emplace_back(all.data() + at, size);
                at += size;
            }
            auto whole = assembler->assemble(done, n, parts, names);
            if (whole) {
                for (std::size_t k = 0; k < sinks.size() && consumed; ++k) {
                    if (!is_shared(k)) consumed = sinks[k]->consume(whole.value());
                }
            } else {
                consumed = whole.error();
            }
        }
        done += n;
        if (root && options.bake.progress) options.bake.progress(done, frames);
    }
    KW_TRY(comm.agree(consumed));
    KW_TRY(comm.agree(options.bake.simulated ? options.bake.simulated() : Result<void>{}));

    // The sinks finish in order: a shared one on every rank at once (its status is the
    // same everywhere), the others on rank 0, each agreed before the next.
    std::vector<BakeOutput> written;
    for (std::size_t k = 0; k < shared.size(); ++k) {
        Result<std::vector<BakeOutput>> files = std::vector<BakeOutput>{};
        if (is_shared(k)) {
            files = sinks[k]->finish_shared(comm);
            if (!files) return files.error();
        } else {
            if (root) files = sinks[k]->finish();
            KW_TRY(comm.agree(files ? Result<void>{} : Result<void>{files.error()}));
        }
        for (BakeOutput& file : files.value()) {
            if (root && !not_shared[k].empty()) {
                file.description += (file.description.empty() ? "" : ", ") + not_shared[k];
            }
            written.push_back(std::move(file));
        }
    }
    return written;
}

}  // namespace kodawari
