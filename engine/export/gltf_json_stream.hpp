#pragma once
// A .glb whose JSON is written element by element: the big arrays of a large export
// (nodes, accessors, a skin, channels and samplers per bird) come from generators and are
// serialized one element at a time, so neither the model's nlohmann DOM nor its JSON
// text is ever held whole. The bytes are the ones tinygltf writes for the same model
// with the generated elements inside it (tests/export/test_json_stream.cpp).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <tiny_gltf.h>  // a system header: its warnings are not ours

#include "core/internal_api.hpp"
#include "kodawari/core/atomic_file.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::gltf {

/// Elements appended to one of the model's arrays: `groups` calls of `fill(group, out)`,
/// in order, each appending any number of elements to `out` (which the writer empties
/// before each call). A group is whatever the caller counts in (a bird's 8 accessors), so
/// that a group's size may differ from one to the next.
template <typename T>
struct ElementSource {
    std::size_t groups = 0;
    std::function<void(std::size_t group, std::vector<T>& out)> fill;
};

/// EXT_meshopt_compression's JSON (the spec: KhronosGroup/glTF,
/// extensions/2.0/Vendor/EXT_meshopt_compression), which tinygltf 2.7 does not write (it
/// writes no buffer or buffer view extensions, and a buffer's byteLength only from its
/// data): buffer `fallback` gets byteLength `fallback_bytes`, no uri and the extension's
/// `fallback: true`; the buffer views from `first_view` on get `views`' objects in order.
struct MeshoptJson {
    struct View {
        std::uint64_t byte_offset = 0;  // in buffer 0, the GLB's BIN chunk
        std::uint64_t byte_length = 0;
        std::uint32_t byte_stride = 0;
        std::uint64_t count = 0;
        const char* filter = "NONE";  // NONE is the default: not written
    };
    int fallback = -1;  // -1: none
    std::uint64_t fallback_bytes = 0;
    int first_view = 0;
    std::vector<View> views;
};

/// What is appended to the model's arrays while they are written.
struct StreamedElements {
    ElementSource<tinygltf::Node> nodes;          // after model.nodes
    ElementSource<tinygltf::Accessor> accessors;  // after model.accessors
    ElementSource<tinygltf::Skin> skins;          // after model.skins (a skin per bird)
    // After model.animations[0]'s channels and samplers; the model must then have an
    // animation (an animation without channels is left out by tinygltf, so its name,
    // extras and place come from the model even when every channel is streamed).
    ElementSource<tinygltf::AnimationChannel> channels;
    ElementSource<tinygltf::AnimationSampler> samplers;
    MeshoptJson meshopt;
};

/// Writes into `file` (not committed) the .glb that tinygltf (write_glb(), binary, compact
/// JSON) writes for `model` with `streamed`'s elements appended to its arrays and
/// `tail_bytes` more bytes at the end of buffer 0, which `write_tail` appends to `file`.
/// The JSON waits in a temporary file beside `file` (its length comes first in the .glb).
/// Buffer 0 must be embedded (no uri) when there is one; without buffers the tail must be
/// empty. tinygltf and nlohmann may throw; callers catch (write_file_atomically()).
[[nodiscard]] KODAWARI_INTERNAL Result<void> write_streamed_glb(AtomicFile& file, tinygltf::Model& model,
                                                                const StreamedElements& streamed,
                                                                std::uint64_t tail_bytes,
                                                                const std::function<Result<void>()>& write_tail);

}  // namespace kodawari::gltf
