#pragma once
// What the benchmarks of `kodawari bench` share across files.

#include <functional>
#include <string>

#include "cli_common.hpp"

namespace kodawari::cli {

/// `s` as the inside of a JSON string.
[[nodiscard]] std::string json_escape(const std::string& s);

/// Writes a benchmark's JSON atomically and says so; the exit code.
int write_json(const std::string& path, const std::string& text);

/// Adds `bench view` to `bench`; `run` runs it once parsed.
CLI::App* add_bench_view(CLI::App& bench, std::function<int()>& run);

}  // namespace kodawari::cli
