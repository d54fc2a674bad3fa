#pragma once
// A compacted .glb written by the ranks of a distributed bake together (docs/scale-out.md,
// issue 34): every rank has compacted its own items' channels (CompactKeys::build over
// its contiguous run of the file's items); rank 0 joins their records onto its own,
// writes the header, the JSON and its own keys leaving room for the others', and names
// its temporary file; each other rank writes its keys there at the place agreed; rank 0
// renames the file into place once every rank has said it wrote. The same bytes as one
// writer that compacted every item. Used by the birds' writer and the rigged characters'.

#include <cstddef>
#include <functional>
#include <span>
#include <string>

#include "export/compact_keys.hpp"
#include "kodawari/core/communicator.hpp"

namespace kodawari::gltf {

/// Whether `path` names a device or a pipe: a file several processes cannot write into.
[[nodiscard]] bool is_device_or_pipe(const std::string& path);

/// A writer's share(begin, end) checked: InvalidInput naming `path` when the writer
/// cannot share (`shareable` false: it needs `needs`), or [begin, end) is not a range of
/// its `count` `items` given before the first frame (`started`).
[[nodiscard]] Result<void> check_share(const std::string& path, bool shareable, const char* needs, const char* items,
                                       std::size_t begin, std::size_t end, std::size_t count, bool started);

/// Collective: every rank calls it once, with its own compacted keys (or the error that
/// stopped it compacting them) and `extra`, bytes of its own that rank 0's file needs
/// (rest poses, which channels exist). Rank 0: `take_extra(rank, bytes)` receives every
/// other rank's in rank order, then `write(file, keys)` writes the whole file with the
/// joined keys (CompactKeys::write() inside, which leaves the others' room). Every step
/// that can fail on one rank ends in an agreement, so that no rank waits in a gather or
/// broadcast another has left; every rank returns the same status. Errors name `path`.
[[nodiscard]] Result<void> finish_shared_glb(Communicator& ranks, const std::string& path, Result<CompactKeys> mine,
                                             std::span<const std::byte> extra,
                                             const std::function<Result<void>(std::size_t rank, std::span<const std::byte> extra)>& take_extra,
                                             const std::function<Result<void>(AtomicFile& file, CompactKeys& keys)>& write);

}  // namespace kodawari::gltf
