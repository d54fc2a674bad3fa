#pragma once
// Shared pieces of the command line: argument reading, backend choice, exit codes.

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "kodawari/backend.hpp"
#include "kodawari/rod_backend.hpp"
#include "kodawari/result.hpp"
#include "kodawari/scene.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/simulation.hpp"

namespace kodawari::cli {

/// Exit codes: 0 success, 1 failure (a check did not pass, a runtime error), 2 bad
/// input or usage.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitBadInput = 2;

/// The scene `make run` and a bare `kodawari run` use.
inline constexpr const char* kDefaultScene = "scenes/flock.json";

/// Thrown for usage errors; main() prints it with the usage and exits 2.
struct UsageError {
    std::string message;
};

/// A simple argument reader: `--name value` options, flags and positionals.
class Args {
public:
    Args(std::vector<std::string> args) : args_(std::move(args)) {}  // NOLINT
    /// Value of `--name VALUE` (or --name=VALUE), removed from the list.
    std::optional<std::string> option(const std::string& name);
    /// Presence of `--name`, removed from the list.
    bool flag(const std::string& name);
    /// `--name` (gives an empty optional) or `--name=VALUE` (gives VALUE, maybe ""),
    /// removed from the list; nullopt when absent. An option whose value is optional, so
    /// never taken from the next argument.
    std::optional<std::optional<std::string>> flag_or_value(const std::string& name);
    /// Unsigned integer option with a range check.
    std::optional<std::uint64_t> count(const std::string& name, std::uint64_t min, std::uint64_t max);
    /// What is left; unknown `--options` are usage errors.
    std::vector<std::string> positionals() const;
    /// The first argument that is not an `--option` ("" when none), without checking the rest.
    std::string first_word() const;

private:
    std::vector<std::string> args_;
};

/// The value of `--size WxH` (an image in pixels, each in [1, 8192]); (1280, 720) when
/// the option is absent. A bad value is a UsageError that names it.
std::pair<std::uint32_t, std::uint32_t> image_size(const std::optional<std::string>& text);

/// Options common to commands that run a simulation.
struct BackendChoice {
    std::optional<BackendKind> backend;  ///< none: auto (vulkan when a device opens, else cpu)
    BackendOptions options;
};
/// --backend, --device, --threads, --isa, --validation; and the environment, which only the
/// command line reads (the library takes options): KODAWARI_DEVICE (the device when no
/// --device), KODAWARI_ISA (the cpu backend's SIMD instruction set when no --isa),
/// KODAWARI_VALIDATION=1 (as --validation), KODAWARI_FORCE_STAGING=1.
BackendChoice read_backend_choice(Args& args);

/// The value of an environment variable ("" when unset); a flag is set unless "" or "0".
[[nodiscard]] std::string env_text(const char* name);
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

/// The one scene file among a command's positionals (kDefaultScene when none).
[[nodiscard]] std::string scene_argument(const std::vector<std::string>& positionals, const char* command);

/// True (after saying so on stderr) when Vulkan validation reported messages: the
/// command then exits kExitFailure. Backends sharing one device share its count, so a
/// caller passes that count once (or the largest of theirs).
[[nodiscard]] bool validation_failed(std::uint32_t messages);

/// Prints an error and returns its exit code.
int report(const Error& error);

/// True when stderr is a terminal (progress bars).
bool stderr_is_terminal();

/// Draws a progress bar line on stderr.
void progress(const char* what, std::uint64_t done, std::uint64_t total);

}  // namespace kodawari::cli
