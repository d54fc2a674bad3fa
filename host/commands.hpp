#pragma once
// The subcommands of `kodawari`. Each add_* defines its subcommand's options on the
// App (CLI11) and returns what runs it once the command line is parsed.

#include <functional>
#include <vector>

#include "cli_common.hpp"

namespace kodawari::cli {

/// A subcommand: its App, and the action that runs it (the process exit code) when the
/// command line named it.
struct Command {
    CLI::App* app = nullptr;
    std::function<int()> run;
};

Command add_run(CLI::App& app);
Command add_merge(CLI::App& app);
Command add_validate(CLI::App& app);
Command add_info(CLI::App& app);
Command add_bench(CLI::App& app);
Command add_rig(CLI::App& app);
Command add_sketch(CLI::App& app);
Command add_render(CLI::App& app);
Command add_view(CLI::App& app);
Command add_schema(CLI::App& app);
Command add_completion(CLI::App& app);

/// `kodawari completion bash`: a bash completion script of `app`'s commands and options.
[[nodiscard]] std::string bash_completion(const CLI::App& app);

}  // namespace kodawari::cli
