// MPI's world as a Communicator (mpi_communicator.hpp). MPI's default error handler
// (MPI_ERRORS_ARE_FATAL) stays: a failed collective is a broken job, which mpirun ends on
// every rank; errors of the bake itself travel through agree().
#include "mpi_communicator.hpp"

#include "kodawari/core/atomic_file.hpp"

#include <climits>
#include <cstdio>
#include <cstdint>
#include <string>

#include <mpi.h>

namespace kodawari::cli {

namespace {

class MpiWorld final : public Communicator {
public:
    MpiWorld() {
        MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
        MPI_Comm_size(MPI_COMM_WORLD, &size_);
        // The ranks that share this machine's memory are the ones that share its devices.
        MPI_Comm node;
        MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &node);
        MPI_Comm_rank(node, &local_rank_);
        MPI_Comm_free(&node);
    }
    ~MpiWorld() override { MPI_Finalize(); }
    MpiWorld(const MpiWorld&) = delete;
    MpiWorld& operator=(const MpiWorld&) = delete;

    int rank() const override { return rank_; }
    int size() const override { return size_; }
    int local_rank() const override { return local_rank_; }

    Result<void> agree(const Result<void>& mine) override {
        // The lowest failing rank, or size_ when none failed.
        int status = mine ? size_ : rank_;
        int first = size_;
        MPI_Allreduce(&status, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
        if (first == size_) return {};
        std::string message = first == rank_ ? mine.error().message : std::string();
        int kind = first == rank_ ? static_cast<int>(mine.error().kind) : 0;
        int length = static_cast<int>(message.size());
        MPI_Bcast(&kind, 1, MPI_INT, first, MPI_COMM_WORLD);
        MPI_Bcast(&length, 1, MPI_INT, first, MPI_COMM_WORLD);
        message.resize(static_cast<std::size_t>(length));
        MPI_Bcast(message.data(), length, MPI_CHAR, first, MPI_COMM_WORLD);
        // An empty message means "already reported" (validation): keep it empty.
        if (size_ > 1 && !message.empty()) message = "rank " + std::to_string(first) + ": " + message;
        return Error{static_cast<Error::Kind>(kind), message};
    }

    void gather(std::span<const std::byte> mine, std::vector<std::byte>& all, std::vector<std::size_t>& sizes) override {
        // A rank's chunk is at most 2^18 bird poses or one frame of its chains, far below
        // MPI's int counts; a larger one is a bug in the chunking.
        if (mine.size() > static_cast<std::size_t>(INT_MAX)) {
            std::fprintf(stderr, "kodawari: internal error: rank %d sends %zu bytes at once, more than MPI counts\n", rank_, mine.size());
            MPI_Abort(MPI_COMM_WORLD, 1);
        }
        const auto count = static_cast<int>(mine.size());
        // Sized on every rank (only rank 0's are read): MPI ignores them elsewhere.
        std::vector<int> counts(static_cast<std::size_t>(size_), 0);
        std::vector<int> offsets(static_cast<std::size_t>(size_), 0);
        MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
        if (rank_ == 0) {
            sizes.assign(counts.begin(), counts.end());
            std::int64_t total = 0;
            for (std::size_t r = 0; r < counts.size(); ++r) {
                offsets[r] = static_cast<int>(total);
                total += counts[r];
            }
            all.resize(static_cast<std::size_t>(total));
        }
        MPI_Gatherv(mine.data(), count, MPI_BYTE, all.data(), counts.data(), offsets.data(), MPI_BYTE, 0, MPI_COMM_WORLD);
    }

    void broadcast(std::vector<std::byte>& data) override {
        std::uint64_t size = data.size();
        MPI_Bcast(&size, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
        data.resize(size);
        MPI_Bcast(data.data(), static_cast<int>(size), MPI_BYTE, 0, MPI_COMM_WORLD);
    }

private:
    int rank_ = 0;
    int size_ = 1;
    int local_rank_ = 0;
};

}  // namespace

Result<std::unique_ptr<Communicator>> open_mpi_world() {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (!initialized && MPI_Init(nullptr, nullptr) != MPI_SUCCESS) {
        return make_error(Error::Kind::Io, "--mpi: MPI_Init failed");
    }
    // MPI_Init may take SIGINT and SIGTERM for itself: ours come back, so that a rank
    // ended by mpirun's SIGTERM still removes its temporary outputs.
    remove_temporary_files_on_signals();
    return std::unique_ptr<Communicator>(std::make_unique<MpiWorld>());
}

}  // namespace kodawari::cli
