#pragma once
// The subcommands of `kodawari`; each returns the process exit code.

#include "cli_common.hpp"

namespace kodawari::cli {

int cmd_run(Args args);
int cmd_merge(Args args);
int cmd_validate(Args args);
int cmd_info(Args args);
int cmd_bench(Args args);
int cmd_rig(Args args);
int cmd_sketch(Args args);
int cmd_render(Args args);
int cmd_view(Args args);
int cmd_schema(Args args);

}  // namespace kodawari::cli
