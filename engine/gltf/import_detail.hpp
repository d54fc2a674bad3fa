#pragma once
// What the files of the glTF import share (not public): the error context, the parse of
// the container, the accessor readers and the loaders of each part of a Character.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <tiny_gltf.h>  // a system header: its warnings are not ours

#include "kodawari/animation/character.hpp"

namespace kodawari::gltf::detail {

// Builds the errors of one file.
struct Context {
    std::string file;

    [[nodiscard]] Error invalid(const std::string& path, const std::string& what) const {
        return make_error(Error::Kind::InvalidInput, file + ": " + path + ": " + what);
    }
    [[nodiscard]] Error unsupported(const std::string& path, const std::string& what) const {
        return make_error(Error::Kind::Unsupported, file + ": " + path + ": " + what);
    }
};

inline std::string at(const std::string& path, std::size_t index) { return path + "[" + std::to_string(index) + "]"; }

#define KW_GLTF_ASSIGN(lhs, expr)                       \
    do {                                                \
        auto kw_gltf_result_ = (expr);                  \
        if (!kw_gltf_result_.ok()) return kw_gltf_result_.error(); \
        (lhs) = std::move(kw_gltf_result_).value();     \
    } while (false)

// glb.cpp: the file's bytes (GLB or JSON) to a tinygltf model, its buffers checked first.
// Also sets `extensions` to the root `extensions` object as JSON text ("" when absent).
Result<tinygltf::Model> parse(const Context& ctx, const std::vector<unsigned char>& bytes, const std::filesystem::path& base_dir,
                              std::string& extensions);

// accessors.cpp: the accessors' storage checks and their readers.
std::size_t component_count(int type);
std::string type_name(int type);
// Every bufferView inside its buffer and every accessor inside its bufferView
// (§3.6.1, §3.6.2), so that reading any accessor later is in bounds.
Result<void> check_storage(const Context& ctx, const tinygltf::Model& model);
// Reads an accessor (checked by check_storage) as floats, normalized integers mapped as
// in §3.11's table (signed: max(c / max, -1)).
Result<std::vector<float>> read_floats(const Context& ctx, const tinygltf::Model& model, int index,
                                       const std::string& where, bool allow_normalized);
const tinygltf::Accessor& accessor_of(const tinygltf::Model& model, int index);
// Reads an accessor (checked by check_storage) of unsigned integers (UNSIGNED_BYTE,
// UNSIGNED_SHORT or UNSIGNED_INT, not normalized): indices and JOINTS_0 (§3.7.2.1).
Result<std::vector<std::uint32_t>> read_uints(const Context& ctx, const tinygltf::Model& model, int index,
                                              const std::string& where);

// mesh_import.cpp, skin_import.cpp, animation_import.cpp: the parts of a Character, each
// checked against the model (load_nodes, in import.cpp, comes before skins and animations).
// Mesh geometry for display (§3.7.2): TRIANGLES primitives with POSITION, and NORMAL,
// JOINTS_0 and WEIGHTS_0 where given.
Result<void> load_meshes(const Context& ctx, const tinygltf::Model& model, animation::Character& out);
Result<void> load_skins(const Context& ctx, const tinygltf::Model& model, animation::Character& out);
Result<void> load_animations(const Context& ctx, const tinygltf::Model& model, animation::Character& out);

}  // namespace kodawari::gltf::detail
