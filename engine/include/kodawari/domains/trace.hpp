#pragma once
/// @file
/// The JSON Lines trace of a bake (docs/trace-format.md): the scene's birds and chains,
/// with their diagnostics, frame by frame.

#include <memory>
#include <string>

#include "kodawari/core/api.hpp"
#include "kodawari/simulation/bake.hpp"

namespace kodawari {

/// A JSON Lines trace (docs/trace-format.md) of birds and chains at `path`.
[[nodiscard]] KODAWARI_API std::unique_ptr<BakeSink> make_trace_sink(std::string path);

}  // namespace kodawari
