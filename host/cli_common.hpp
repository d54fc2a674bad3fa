#pragma once
// Shared pieces of the command line: option definitions (CLI11), backend choice, exit codes.

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "kodawari/backends/backend.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/simulation/simulation.hpp"

namespace kodawari::cli {

/// Exit codes: 0 success, 1 failure (a check did not pass, a runtime error), 2 bad
/// input or usage.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitBadInput = 2;

/// The scene `make run` and a bare `kodawari run` use.
inline constexpr const char* kDefaultScene = "scenes/flock.json";

/// A shipped scene by its path in the source tree (`scenes/crowd.json`): there, relative
/// to the current folder, else where an installed command keeps them
/// (<prefix>/share/kodawari/scenes, found from the command's own path); a UsageError
/// naming both places when neither has it.
[[nodiscard]] std::string shipped_scene(const std::string& relative);

/// The scene a command was given, else kDefaultScene; a UsageError saying that no scene
/// was given when the default is not there either (a command run outside the source
/// tree, from an installed package), rather than that scenes/flock.json cannot be opened.
[[nodiscard]] std::string scene_or_default(const std::optional<std::string>& scene);

/// Thrown for usage errors that CLI11 cannot check (options that exclude each other, a value
/// checked against the scene); main() prints it with a pointer to --help and exits 2.
struct UsageError {
    std::string message;
};

/// The options of a command are bound to a CLI11 App; the helpers below give every command
/// the same spelling, value names and messages for the same things. A description says the
/// default in "(default: ...)" so that `--help` lists it.

/// `--name VALUE`: `into` holds the value when given.
CLI::Option* add_text(CLI::App& app, const std::string& names, std::optional<std::string>& into, const std::string& value_name,
                      const std::string& description);
/// `--name N`: an integer in [min, max] (a bad value is a usage error naming the option and
/// the range).
CLI::Option* add_count(CLI::App& app, const std::string& names, std::optional<std::uint64_t>& into, std::uint64_t min,
                       std::uint64_t max, const std::string& description);
/// `--name`, a flag.
CLI::Option* add_switch(CLI::App& app, const std::string& names, bool& into, const std::string& description);
/// `--size WxH` (image_size() reads it).
CLI::Option* add_size(CLI::App& app, std::optional<std::string>& into, const std::string& what);
/// `NAME`, an optional positional scene file (kDefaultScene when absent unless `default_scene` says otherwise).
CLI::Option* add_scene(CLI::App& app, std::optional<std::string>& into, const std::string& default_scene = kDefaultScene);

/// A renamed option's old spelling, kept for one release: `old_value` is its value; says on
/// stderr that it is deprecated and gives it to `value` (a usage error when both are given).
template <typename T>
void take_alias(std::optional<T>& value, const std::optional<T>& old_value, const std::string& old_name, const std::string& name) {
    if (!old_value) return;
    if (value) throw UsageError{old_name + " is the old spelling of " + name + ": give one of them"};
    std::fprintf(stderr, "kodawari: %s is deprecated (it goes in the next release); use %s\n", old_name.c_str(), name.c_str());
    value = old_value;
}

/// The value of `--size WxH` (an image in pixels, each in [1, 8192]); (1280, 720) when
/// the option is absent. A bad value is a UsageError that names it.
std::pair<std::uint32_t, std::uint32_t> image_size(const std::optional<std::string>& text);
/// `option`'s value WxH, each in [1, max]: a UsageError naming the option and the bounds
/// otherwise.
std::pair<std::uint32_t, std::uint32_t> parse_image_size(const std::string& option, const std::string& text,
                                                         std::uint32_t max_width, std::uint32_t max_height);
/// `option`'s value as a finite number: a UsageError naming the option otherwise.
float parse_real(const std::string& option, const std::string& text);

/// The backend options as given: --backend, --device, --threads, --isa, --validation.
struct BackendFlags {
    std::optional<std::string> backend;
    std::optional<std::string> device;
    std::optional<std::uint64_t> threads;
    std::optional<std::string> isa;
    std::optional<std::uint64_t> workgroup_size;
    bool validation = false;
};
/// Adds the backend options to a command that runs a simulation.
void add_backend_options(CLI::App& app, BackendFlags& flags);

/// --lod and --lod-bias: levels of detail of the characters' chains (docs/level-of-detail.md).
struct LodFlags {
    bool lod = false;
    std::optional<std::string> bias;
    bool every_frame = false;
    std::optional<std::string> budget_ms;
    std::optional<std::string> reduced;
};
void add_lod_options(CLI::App& app, LodFlags& flags);
/// The flags applied to `scene`'s settings: --lod turns them on (the scene's `lod`, or the
/// defaults), --lod-bias sets the bias (a UsageError outside [-8, 8]), --lod-reduced the
/// reduced level's pixels (0: off; a UsageError unless below the full level's).
/// --budget-ms turns them on with the scene's `lod.budget_ms` set (priced by the cost
/// model: a bake's levels never depend on the wall clock); a UsageError unless a positive
/// finite number of ms, at most 100000.
void apply_lod(const LodFlags& flags, Scene& scene);
/// For `view` and `bench`: --budget-ms measured, the model scaled by what the frames take
/// on this machine (set_lod_budget(sim, ms, true)); nothing without it.
[[nodiscard]] Result<void> apply_measured_budget(const LodFlags& flags, Simulation& sim);

/// Options common to commands that run a simulation.
struct BackendChoice {
    std::optional<BackendKind> backend;  ///< none: auto (vulkan on a GPU, else cpu)
    BackendOptions options;
};
/// --backend, --device, --threads, --isa, --workgroup-size, --validation; and the environment, which only the
/// command line reads (the library takes options): KODAWARI_DEVICE (the device when no
/// --device), KODAWARI_ISA (the cpu backend's SIMD instruction set when no --isa),
/// KODAWARI_VALIDATION=1 (as --validation), KODAWARI_FORCE_STAGING=1.
BackendChoice read_backend_choice(const BackendFlags& flags);

/// The value of an environment variable ("" when unset); a flag is set unless "" or "0".
[[nodiscard]] std::string env_text(const char* name);

/// "1 bird", "270 birds": `count` and `noun` (singular), an "s" added unless it is 1.
[[nodiscard]] std::string counted(std::size_t count, std::string_view noun);
[[nodiscard]] bool env_flag(const char* name);

/// A renderer of width x height on the device, validation and staging of `choice`.
[[nodiscard]] render::RendererOptions renderer_options(const BackendChoice& choice, std::uint32_t width, std::uint32_t height);

/// The Simulation of a scene file (`command` names the command in usage errors) or of a
/// parsed scene, on the backends of `choice`, `frames` long (none: the scene's). When
/// "auto" falls back to the CPU it says why in one line on stderr.
/// `shard`: the part of the scene's instances to simulate (default: all).
[[nodiscard]] Result<std::unique_ptr<Simulation>> open_simulation(const std::string& path, const BackendChoice& choice,
                                                                  std::optional<std::uint64_t> frames, Shard shard = {});
[[nodiscard]] Result<std::unique_ptr<Simulation>> make_simulation(Scene scene, const BackendChoice& choice,
                                                                  std::optional<std::uint64_t> frames, Shard shard = {});

/// --strict and --fit-routes of `run` and `validate`.
void add_route_check_options(CLI::App& app, bool& strict, bool& fit);

/// The route check of `run` and `validate` (kodawari/scene/route_check.hpp, --strict and
/// --fit-routes): with `fit`, fits the flocks' timing first and says what changed on
/// stdout; then warns on stderr about every route that exceeds its bird's limits. Returns
/// the exit code to stop with (a scene that does not build, or warnings under `strict`),
/// or none to go on. Also prints the rigged characters' warnings (RigSpec::warnings).
/// `print` false: the same checks and fit, silently (the ranks of `run --mpi` but rank 0).
[[nodiscard]] std::optional<int> check_scene_routes(Scene& scene, bool strict, bool fit, bool print = true);

/// True (after saying so on stderr) when Vulkan validation reported messages: the
/// command then exits kExitFailure. Backends sharing one device share its count, so a
/// caller passes that count once (or the largest of theirs).
[[nodiscard]] bool validation_failed(std::uint32_t messages);

/// The exit code of an error: kExitBadInput for bad input (a bad option or value, a
/// missing or unreadable input file, content the loader refuses), kExitFailure otherwise.
[[nodiscard]] int exit_code(const Error& error);
/// Prints an error and returns its exit code.
int report(const Error& error);

/// True when stderr is a terminal (progress bars).
bool stderr_is_terminal();

/// Draws a progress bar line on stderr.
void progress(const char* what, std::uint64_t done, std::uint64_t total);

}  // namespace kodawari::cli
