#pragma once
// The files `run`, `merge` and a distributed run bake a scene into, chosen one way for
// all three so that they write the same files.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "kodawari/simulation/bake.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"

namespace kodawari::cli {

/// The `.glb` sinks of a scene: the birds at `out`; the characters at `out` too when
/// there are no birds, else at `<out without .glb>-characters.glb`; their keys compacted
/// as `compaction` says.
[[nodiscard]] std::vector<std::unique_ptr<BakeSink>> glb_sinks(const std::string& out, bool has_birds, bool has_chains,
                                                               const GlbCompaction& compaction);

/// A UsageError naming --out when `out` is given and not named .glb (any case): what the
/// glTF sinks write is a binary glTF file, and a reader goes by the name. A device or a
/// pipe (an existing file that is not a regular one) passes.
void require_glb_name(const std::optional<std::string>& out);

/// An InvalidInput error when one of `outputs` is the scene file or a file the scene read
/// (Scene::inputs: its models, motions, maps): a bake written there would replace its
/// own input, and the next run would read the bake. `what` says where the path came
/// from ("--out", "the default output"); the message suggests another path with
/// `extension` (".glb", ".kwpart"; ".jsonl": a --trace).
[[nodiscard]] Result<void> refuse_overwriting_inputs(const Scene& scene, const std::vector<std::string>& outputs,
                                                     const std::string& what, const std::string& extension);

/// Adds `--compact[=METRES[,RADIANS]]` (docs/compact.md), whose value `into` holds, and
/// `--meshopt`, which sets `meshopt`.
CLI::Option* add_compaction_option(CLI::App& app, std::optional<std::string>& into, bool& meshopt);
/// The compaction `--compact` (and `--meshopt`) ask for; not enabled when absent. A bad
/// value is a UsageError naming --compact; `--meshopt` without `--compact`, one naming
/// --meshopt.
[[nodiscard]] GlbCompaction read_compaction(const std::optional<std::string>& option, bool meshopt = false);

/// `out/<scene name>.glb`, creating `out/` (the default output).
[[nodiscard]] std::string default_output(const std::string& scene_name, const std::string& extension = ".glb");

/// Creates the folder of an output file (and its parents) when missing, as `render --out`
/// does; an Io error naming `option` and the folder when it cannot.
[[nodiscard]] Result<void> make_parent_folder(const std::string& path, const std::string& option);

/// "kodawari: wrote FILE (N MiB, ...)", and for a compacted file what compaction did.
void print_wrote(const BakeOutput& file);

/// Pointers to the sinks, for bake().
[[nodiscard]] std::vector<BakeSink*> sink_pointers(const std::vector<std::unique_ptr<BakeSink>>& sinks);

}  // namespace kodawari::cli
