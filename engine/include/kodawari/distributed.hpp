#pragma once
/// @file
/// One bake spread over the ranks of a distributed job (issue 15): rank r simulates shard
/// r of N (SimulationOptions::shard), every rank's frames are gathered chunk by chunk to
/// rank 0, and rank 0 alone feeds the sinks: its files are those of a single-process bake,
/// byte for byte, and no rank ever holds more than one chunk of frames. An error on any
/// rank stops every rank with that rank's message, and the sinks leave no file.
///
/// The engine speaks to the job through Communicator; the `kodawari` command implements
/// it with MPI (`kodawari run SCENE --mpi` under `mpirun`), and an application with a job
/// system of its own can implement it too.

#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "kodawari/api.hpp"
#include "bake.hpp"
#include "result.hpp"
#include "simulation.hpp"

namespace kodawari {

/// The ranks of a job. Every call but the accessors is collective: every rank makes the
/// same calls in the same order.
class KODAWARI_API Communicator {
public:
    virtual ~Communicator() = default;
    [[nodiscard]] virtual int rank() const = 0;
    [[nodiscard]] virtual int size() const = 0;
    /// The rank among the ranks on this machine (chooses a Vulkan device), and their count.
    [[nodiscard]] virtual int local_rank() const = 0;
    /// Every rank hands its status; all get success, or the error of the lowest failing
    /// rank, its message prefixed "rank R: " when there are several ranks.
    [[nodiscard]] virtual Result<void> agree(const Result<void>& mine) = 0;
    /// Rank 0 receives every rank's bytes, rank after rank, into `all` (sizes in `sizes`);
    /// the other ranks' `all` and `sizes` are untouched.
    virtual void gather(std::span<const std::byte> mine, std::vector<std::byte>& all, std::vector<std::size_t>& sizes) = 0;
    /// Rank 0's `data` (size included) on every rank.
    virtual void broadcast(std::vector<std::byte>& data) = 0;
};

/// What bake_distributed() runs.
struct DistributedBakeOptions {
    /// Every rank's simulation; `shard` is set by rank. With the vulkan (or auto) backend
    /// and no device given, the ranks on one machine take different devices, by local
    /// rank, among the devices of the type the engine would choose (discrete GPUs, say),
    /// when there are several.
    SimulationOptions simulation;
    /// Called on rank 0 with the whole scene's world: the sinks to feed (kept alive by
    /// the caller's unique_ptrs, which it returns).
    std::function<std::vector<std::unique_ptr<BakeSink>>(const BakeWorld& world)> make_sinks;
    /// Rank 0's progress; `simulated` runs on every rank after the last frame (its
    /// errors stop every rank).
    BakeOptions bake;
    /// Called on every rank once its simulation is open (to print what it runs).
    std::function<void(const Simulation&)> opened;
    /// When set, called on every rank with the loaded scene before its simulation opens,
    /// to change it the same way on every rank (the command line fits the flocks' routes
    /// here: `run --mpi --fit-routes`); an error stops every rank. The change must be a
    /// function of the scene alone, or the ranks would bake different scenes.
    std::function<Result<void>(Scene& scene)> prepare_scene;
};

/// Bakes the scene at `scene_path` over `comm`'s ranks. Returns rank 0's files (the other
/// ranks: none). Errors: any rank's (the scene, a device, a sink, a full disk), the same on
/// every rank.
[[nodiscard]] KODAWARI_API Result<std::vector<BakeOutput>> bake_distributed(Communicator& comm, const std::string& scene_path,
                                                                            const DistributedBakeOptions& options);

}  // namespace kodawari
