#pragma once
/// @file
/// glTF 2.0 import of a rigged character (kodawari::io, which compiles tinygltf): the
/// Character data and its animation sampling are kodawari::sim's (character.hpp).

#include <string>

#include "kodawari/core/api.hpp"
#include "kodawari/animation/character.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::gltf {

/// Loads a `.gltf` (JSON, external or data-URI buffers) or `.glb` (binary) character.
/// Errors name the file and the glTF path of the problem ("a.gltf: $.skins[0].joints[3]:
/// node 17 does not exist"); Error::Kind::Io when the file cannot be read,
/// InvalidInput for everything wrong inside it (including external buffers that are
/// missing). Never throws.
[[nodiscard]] KODAWARI_API Result<animation::Character> load_character(const std::string& path);

}  // namespace kodawari::gltf
