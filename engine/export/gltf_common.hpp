#pragma once
// Pieces shared by the glTF writers (gltf_birds.cpp, gltf_chains.cpp): meshes, the
// model's single buffer, accessors, and streaming a .glb into an AtomicFile.

#include <array>
#include <functional>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <streambuf>
#include <vector>

#include <tiny_gltf.h>  // a system header: its warnings are not ours

#include "core/flat_mesh.hpp"
#include "kodawari/core/atomic_file.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::gltf {

struct MeshoptJson;  // gltf_json_stream.hpp

using Vec3 = std::array<float, 3>;
using Quat = std::array<float, 4>;

inline constexpr int kArrayBuffer = TINYGLTF_TARGET_ARRAY_BUFFER;
inline constexpr int kElementArrayBuffer = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;

// The meshes the writers add are the flat meshes of core/flat_mesh.hpp (shared with the
// birds' part geometry and the renderer).
using core::MeshData;
using core::box;

/// Writes into the one buffer of the model; every block starts 4-byte aligned.
class BufferWriter {
public:
    explicit BufferWriter(std::vector<unsigned char>& bytes) : bytes_(bytes) {}
    /// Reserves `size` bytes (zeroed) and returns their offset.
    std::size_t allocate(std::size_t size);
    /// Copies `size` bytes in and returns their offset.
    std::size_t append(const void* data, std::size_t size);

private:
    std::vector<unsigned char>& bytes_;
};

[[nodiscard]] int add_buffer_view(tinygltf::Model& model, std::size_t offset, std::size_t length, int target);
[[nodiscard]] int add_accessor(tinygltf::Model& model, int view, std::size_t offset, int component, std::size_t count,
                               int type);
/// Float VEC3 accessor with its own ARRAY_BUFFER view, min/max filled in.
[[nodiscard]] int add_vec3_attribute(tinygltf::Model& model, BufferWriter& writer, const std::vector<Vec3>& values);
/// A mesh of one triangle primitive with positions, normals and indices.
[[nodiscard]] int add_mesh(tinygltf::Model& model, BufferWriter& writer, const MeshData& data, int material,
                           const std::string& name);

/// Serializes `model` as a .glb into `file` (not committed). tinygltf may throw; callers
/// catch.
[[nodiscard]] Result<void> write_glb(AtomicFile& file, tinygltf::Model& model);

/// Serializes `model` as a .glb into `file` (not committed) whose one buffer is
/// model.buffers[0].data followed by `tail_bytes` more that `write_tail` appends to
/// `file`: the bytes write_glb() would write with the tail in the buffer, without holding
/// the tail in memory (write_streamed_glb() with nothing streamed: the JSON waits in a
/// temporary file beside `file`). tinygltf may throw; callers catch.
/// `meshopt`: EXT_meshopt_compression's JSON when the tail holds meshopt streams
/// (gltf_json_stream.hpp).
[[nodiscard]] Result<void> write_glb_with_tail(AtomicFile& file, tinygltf::Model& model, std::uint64_t tail_bytes,
                                               const std::function<Result<void>()>& write_tail,
                                               const MeshoptJson* meshopt = nullptr);

/// Data that arrives in another order than a file wants it (keys frame by frame, a
/// .glb's channels each contiguous) wait here: a file beside the output, on the disk
/// meant to hold that much, unlinked as soon as it is open so that it goes with the
/// process whatever happens.
class SpillFile {
public:
    /// Creates `<beside>.keys-<pid>`; `beside` empty, or a device or a pipe: in the
    /// system's temporary directory. Errors name `beside` and the temporary file.
    [[nodiscard]] static Result<SpillFile> open(const std::string& beside);
    SpillFile() = default;
    SpillFile(SpillFile&& other) noexcept;
    SpillFile& operator=(SpillFile&& other) noexcept;
    SpillFile(const SpillFile&) = delete;
    SpillFile& operator=(const SpillFile&) = delete;
    ~SpillFile();

    [[nodiscard]] Result<void> append(const void* data, std::size_t size);
    /// Reads back `size` bytes at `offset` (after the appends).
    [[nodiscard]] Result<void> read(std::uint64_t offset, void* data, std::size_t size);

private:
    [[nodiscard]] std::string spill_error(const std::string& what, const std::string& why) const;

    std::FILE* file_ = nullptr;
    std::string path_;
    std::string serves_;  // the output it is beside, named in errors
    bool reading_ = false;
};

/// Reads items [begin, begin + n) of every frame of `keys` (frames x `count` records of
/// `record_floats` floats, frame-major) into `in`: frame f's n records at
/// in + f * n * record_floats.
[[nodiscard]] Result<void> read_item_group(SpillFile& keys, std::size_t count, std::uint32_t frames, std::size_t record_floats,
                                           std::size_t begin, std::size_t n, float* in);

/// Copies `keys`, frames x `count` records of float fields (`fields`: each field's float
/// count, in record order), frame-major as a simulation produces them, to `file`
/// item-major as a .glb's channels want them: per item, each field's values over all
/// frames, field after field. `keep(item, field)` false leaves a field out (an unscaled
/// node's scale). Works through groups of items of about `group_bytes` (at least one
/// item), so memory does not grow with the frames x items.
[[nodiscard]] Result<void> copy_item_major(SpillFile& keys, AtomicFile& file, std::size_t count, std::uint32_t frames,
                                           std::span<const std::size_t> fields, std::size_t group_bytes,
                                           const std::function<bool(std::size_t item, std::size_t field)>& keep = {});

/// Adds a LINEAR sampler over `input` (key times) and `output` (values) and a channel
/// driving `path` ("translation", "rotation", "scale") of `node` with it.
void add_linear_channel(tinygltf::Animation& animation, int input, int output, int node, const char* path);

/// Opens `path` atomically, runs `build` on it (which writes the whole file), and
/// commits. tinygltf reports some failures (JSON, allocation) by throwing: they become
/// Error::Kind::Io naming `path`, and nothing is left behind.
[[nodiscard]] Result<void> write_file_atomically(const std::string& path, const std::function<Result<void>(AtomicFile&)>& build);

}  // namespace kodawari::gltf
