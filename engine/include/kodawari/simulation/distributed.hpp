#pragma once
/// @file
/// One bake spread over the ranks of a distributed job (issue 15): rank r simulates shard
/// r of N (SimulationOptions::shard). A sink that can share its work
/// (BakeSink::can_share(): a compacted birds' .glb) is made on every rank, fed each
/// rank's own frames, and every rank compacts its own instances' channels and writes them
/// into the file at agreed offsets (issue 34). Every other sink's frames are gathered
/// chunk by chunk to rank 0, which alone feeds it. Either way the files are those of a
/// single-process bake, byte for byte, and no rank ever holds more than one chunk of
/// frames. An error on any rank stops every rank with that rank's message, and the sinks
/// leave no file.
///
/// The engine speaks to the job through Communicator (kodawari/core/communicator.hpp); the
/// `kodawari` command implements it with MPI (`kodawari run SCENE --mpi` under
/// `mpirun`), and an application with a job system of its own can implement it too.

#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/simulation/bake.hpp"
#include "kodawari/core/communicator.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/simulation/simulation.hpp"

namespace kodawari {

/// What bake_distributed() runs.
struct DistributedBakeOptions {
    /// Every rank's simulation; `shard` is set by rank. With the vulkan (or auto) backend
    /// and no device given, the ranks on one machine take different devices, by local
    /// rank, among the devices of the type the engine would choose (discrete GPUs, say),
    /// when there are several.
    SimulationOptions simulation;
    /// The sinks to feed (kept alive by the caller's unique_ptrs, which it returns).
    /// Called on rank 0 with the whole scene's world; then, when some of them can share
    /// their work, on every other rank with the whole scene's world too, where only those
    /// are begun (it must return the same sinks in the same order on every rank).
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
