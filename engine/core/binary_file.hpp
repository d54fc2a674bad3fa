#pragma once
// Reading whole files into memory, with errors that name the file.

#include <string>
#include <vector>

#include "core/internal_api.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::core {

/// The bytes of the file at `path`. Error::Kind::Io naming the file when it cannot be
/// opened (with the system's reason), is a directory, or a read fails.
[[nodiscard]] KODAWARI_INTERNAL Result<std::vector<unsigned char>> read_binary_file(const std::string& path);

}  // namespace kodawari::core
