#pragma once
/// @file
/// The ranks of a distributed job as the engine speaks to them (issue 15): what
/// bake_distributed() (kodawari/simulation/distributed.hpp) runs on, and what a sink that shares its
/// work between the ranks (BakeSink::finish_shared(), kodawari/simulation/bake.hpp) uses to agree
/// where each rank's bytes go. The `kodawari` command implements it with MPI; an
/// application with a job system of its own can implement it too.

#include <cstddef>
#include <span>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"

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

}  // namespace kodawari
