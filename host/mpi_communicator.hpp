#pragma once
// The Communicator of `kodawari run --mpi` (kodawari/simulation/distributed.hpp) over MPI's world.
// Only built when CMake finds MPI (KODAWARI_WITH_MPI).

#include <memory>

#include "kodawari/simulation/distributed.hpp"

namespace kodawari::cli {

/// Initializes MPI (MPI_Init) and finalizes it when destroyed. Errors: MPI fails to start.
[[nodiscard]] Result<std::unique_ptr<Communicator>> open_mpi_world();

}  // namespace kodawari::cli
