#include "cli_common.hpp"

#include "kodawari/scene/route_check.hpp"

#include "kodawari/vulkan/compute.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/vulkan/gpu_info.hpp"
#include "kodawari/backends/simd.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <exception>
#include <unistd.h>

namespace kodawari::cli {

namespace {

// An unsigned integer in [min, max]; nullopt when `text` is not one.
std::optional<std::uint64_t> parse_count(const std::string& text, std::uint64_t min, std::uint64_t max) {
    if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos || text.size() > 19) return std::nullopt;
    const std::uint64_t value = std::stoull(text);
    if (value < min || value > max) return std::nullopt;
    return value;
}

}  // namespace

CLI::Option* add_text(CLI::App& app, const std::string& names, std::optional<std::string>& into, const std::string& value_name,
                      const std::string& description) {
    return app.add_option_function<std::string>(names, [&into](const std::string& value) { into = value; }, description)
        ->type_name(value_name);
}

CLI::Option* add_count(CLI::App& app, const std::string& names, std::optional<std::uint64_t>& into, std::uint64_t min,
                       std::uint64_t max, const std::string& description) {
    // The check runs before the callback, and its message (CLI11 puts the option's name
    // before it) says the range, as every count option of the command line does.
    const CLI::Validator range(
        [min, max](std::string& text) -> std::string {
            if (parse_count(text, min, max)) return "";
            return "expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "], got \"" + text + "\"";
        },
        "");
    return app
        .add_option_function<std::string>(
            names, [&into, min, max](const std::string& text) { into = parse_count(text, min, max); }, description)
        ->type_name("N")
        ->check(range);
}

CLI::Option* add_switch(CLI::App& app, const std::string& names, bool& into, const std::string& description) {
    return app.add_flag(names, into, description);
}

CLI::Option* add_size(CLI::App& app, std::optional<std::string>& into, const std::string& what) {
    return add_text(app, "--size", into, "WxH", what + ", W and H in [1, 8192] pixels (default: 1280x720)");
}

std::string shipped_scene(const std::string& relative) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::exists(relative, ec)) return relative;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);
    const fs::path installed = (self.parent_path() / KODAWARI_DATA_FROM_BIN / relative).lexically_normal();
    if (!ec && fs::exists(installed, ec)) return installed.string();
    throw UsageError{"no scene given, and the default " + relative + " is neither in this folder nor installed (" +
                     (self.empty() ? std::string("<prefix>/share/kodawari/") + relative : installed.string()) +
                     "; the shipped scenes are the source tree's scenes/): give a scene file as the first argument"};
}

std::string scene_or_default(const std::optional<std::string>& scene) {
    if (scene) return *scene;
    return shipped_scene(kDefaultScene);
}

CLI::Option* add_scene(CLI::App& app, std::optional<std::string>& into, const std::string& default_scene) {
    return add_text(app, "scene", into, "SCENE", "the scene file (default: " + default_scene + ")");
}

void add_backend_options(CLI::App& app, BackendFlags& flags) {
    add_text(app, "--backend", flags.backend, "auto|vulkan|cpu|cpu-reference",
             "the simulation's backend (default: auto: vulkan on a GPU, else cpu, also where the only Vulkan device is a CPU such as lavapipe)");
    add_text(app, "--device", flags.device, "NAME|INDEX",
             "the Vulkan device, a name or an index as `kodawari info` lists them (default: $KODAWARI_DEVICE, else "
             "the one `kodawari info` chooses)");
    add_count(app, "--threads", flags.threads, 1, 1024, "the cpu backend's threads, and --compact's encoder's (default: one per hardware thread)");
    add_text(app, "--isa", flags.isa, "avx512|avx2|sse4|scalar",
             "the cpu backend's SIMD instruction set (default: $KODAWARI_ISA, else the widest this CPU runs)");
    add_count(app, "--workgroup-size", flags.workgroup_size, 32, 1024,
              "invocations per workgroup of the vulkan kernels that run one chain, bird or character each, a power of "
              "two the device allows; the results are the same (default: 64)");
    add_switch(app, "--validation", flags.validation,
               "Khronos validation and synchronization validation; messages fail the command (default: off, or "
               "$KODAWARI_VALIDATION=1)");
}

std::string counted(std::size_t count, std::string_view noun) {
    return std::to_string(count) + " " + std::string(noun) + (count == 1 ? "" : "s");
}

std::string env_text(const char* name) {
    const char* value = std::getenv(name);
    return value != nullptr ? value : "";
}

bool env_flag(const char* name) {
    const std::string value = env_text(name);
    return !value.empty() && value != "0";
}

render::RendererOptions renderer_options(const BackendChoice& choice, std::uint32_t width, std::uint32_t height) {
    return {.width = width,
            .height = height,
            .device = choice.options.device,
            .validation = choice.options.validation,
            .force_staging = choice.options.force_staging};
}

BackendChoice read_backend_choice(const BackendFlags& flags) {
    BackendChoice choice;
    if (flags.backend) {
        auto parsed = parse_backend_choice(*flags.backend);
        if (!parsed) throw UsageError{"--" + parsed.error().message};
        choice.backend = parsed.value();
    }
    // The environment is read here and only here; the library takes options.
    choice.options.device = flags.device.value_or(env_text("KODAWARI_DEVICE"));
    if (flags.threads) choice.options.threads = static_cast<unsigned>(*flags.threads);
    // The cpu backend's instruction set: --isa, else KODAWARI_ISA, else the widest (the
    // backend factories reject a name this machine cannot run, naming the ones it can).
    choice.options.isa = flags.isa.value_or(env_text("KODAWARI_ISA"));
    const char* isa_from = flags.isa ? "--isa" : "KODAWARI_ISA";
    if (!choice.options.isa.empty()) {
        if (auto checked = simd_isa(choice.options.isa); !checked) throw UsageError{std::string(isa_from) + ": " + checked.error().message};
    }
    if (flags.workgroup_size) {
        const auto n = *flags.workgroup_size;
        if (!compute::is_workgroup_size(n)) throw UsageError{"--workgroup-size: " + std::to_string(n) + " is not a power of two (32, 64, ... 1024)"};
        choice.options.workgroup_size = static_cast<unsigned>(n);
    }
    choice.options.validation = flags.validation || env_flag("KODAWARI_VALIDATION");
    choice.options.force_staging = env_flag("KODAWARI_FORCE_STAGING");
    return choice;
}

void add_lod_options(CLI::App& app, LodFlags& flags) {
    add_switch(app, "--lod", flags.lod,
               "levels of detail of the characters' chains: full simulation only where the scene camera sees a character large "
               "enough, posed farther, hidden off the view (the scene's `lod` settings, else the defaults; docs/level-of-detail.md) "
               "(default: off, unless the scene's `lod` turns them on)");
    add_text(app, "--lod-bias", flags.bias, "X",
             "log2 of a scale on every character's projected size, in [-8, 8]: +1 simulates as if every character were twice as near "
             "(default: the scene's `lod.bias`, else 0)");
    add_text(app, "--lod-reduced", flags.reduced, "PX",
             "the reduced level: characters below `lod.full_pixels` and down to PX pixels are simulated at half the substeps and "
             "iterations, posed below; 0 turns it off; below `lod.full_pixels` (default: the scene's `lod.reduced_pixels`, else off)");
    add_switch(app, "--lod-every-frame", flags.every_frame,
               "step every posed and hidden chain every frame, as the scene's `lod.lower_rate: false` (default: far posed chains "
               "step every 2nd frame, hidden ones every 4th)");
    add_text(app, "--budget-ms", flags.budget_ms, "MS",
             "the budget mode (turns --lod on): fewer characters full, nearest first, so that a frame's clips and chains stay "
             "within MS milliseconds, in (0, 100000]; `run` and `render` price frames by the scene's cost model (`lod.costs`: "
             "the same bits on every run), `view` and `bench` by what their frames take (default: the scene's `lod.budget_ms`, "
             "else no budget)");
}

void apply_lod(const LodFlags& flags, Scene& scene) {
    if (flags.lod) scene.lod.enabled = true;
    if (flags.every_frame) scene.lod.lower_rate = false;
    if (flags.bias) {
        const float bias = parse_real("--lod-bias", *flags.bias);
        if (!(bias >= -8.0f && bias <= 8.0f)) throw UsageError{"--lod-bias: " + *flags.bias + " is not in [-8, 8]"};
        scene.lod.bias = bias;
    }
    if (flags.reduced) {
        const float pixels = parse_real("--lod-reduced", *flags.reduced);
        if (!(pixels == 0.0f || (pixels > 0.0f && pixels < scene.lod.full_pixels))) {
            char full[32];
            std::snprintf(full, sizeof full, "%g", static_cast<double>(scene.lod.full_pixels));
            throw UsageError{"--lod-reduced: expected 0 (off) or a number of pixels below the scene's lod.full_pixels (" +
                             std::string(full) + "), got " + *flags.reduced};
        }
        scene.lod.reduced_pixels = pixels;
    }
    if (flags.budget_ms) {
        const float ms = parse_real("--budget-ms", *flags.budget_ms);
        if (!(ms > 0.0f && ms <= 100000.0f)) {
            throw UsageError{"--budget-ms: expected a positive number of milliseconds, at most 100000, got " + *flags.budget_ms};
        }
        scene.lod.enabled = true;
        scene.lod.budget_ms = ms;
    }
}

Result<void> apply_measured_budget(const LodFlags& flags, Simulation& sim) {
    if (!flags.budget_ms) return {};
    return set_lod_budget(sim, sim.scene().lod.budget_ms, /*measured=*/true);
}

Result<std::unique_ptr<Simulation>> make_simulation(Scene scene, const BackendChoice& choice, std::optional<std::uint64_t> frames,
                                                    Shard shard) {
    SimulationOptions options{.backend = choice.backend, .options = choice.options, .shard = shard};
    if (frames) options.frames = static_cast<std::uint32_t>(*frames);
    auto sim = Simulation::create(std::move(scene), options);
    if (sim && !sim.value()->fallback_reason().empty()) {
        std::fprintf(stderr, "kodawari: backend auto runs on the CPU: %s\n", sim.value()->fallback_reason().c_str());
    }
    return sim;
}

Result<std::unique_ptr<Simulation>> open_simulation(const std::string& path, const BackendChoice& choice,
                                                    std::optional<std::uint64_t> frames, Shard shard) {
    auto scene = load_scene(path);
    if (!scene) return scene.error();
    return make_simulation(std::move(scene).value(), choice, frames, shard);
}

void add_route_check_options(CLI::App& app, bool& strict, bool& fit) {
    add_switch(app, "--strict", strict,
               "a route beyond its bird's limits (turn, climb, dive, speed change, corner or bank jump at a junction) is an error, exit 2 "
               "(default: off, a warning)");
    add_switch(app, "--fit-routes", fit,
               "smooth the corners of explicit routes, then lower a flock's speed (parametric timing: lengthen its segments) "
               "until its turns, bank jumps and speed changes pass (default: off)");
}

std::optional<int> check_scene_routes(Scene& scene, bool strict, bool fit, bool print) {
    // What the characters' motions could not use (gltf/motion.hpp): notes, never errors.
    for (const CharacterSpec& c : scene.characters) {
        if (!c.rig || !print) continue;
        for (const std::string& w : c.rig->warnings) std::fprintf(stderr, "kodawari: warning: %s\n", w.c_str());
    }
    if (scene.flocks.empty()) return std::nullopt;
    if (fit) {
        auto changes = fit_routes(scene);
        if (!changes) return print ? report(changes.error()) : exit_code(changes.error());
        for (const std::string& line : changes.value()) {
            if (print) std::printf("kodawari: fit: %s\n", line.c_str());
        }
        std::fflush(stdout);
    }
    auto warnings = check_routes(scene);
    if (!warnings) return print ? report(warnings.error()) : exit_code(warnings.error());
    const char* kind = strict ? "error" : "warning";
    // At most kShown lines a flock: a route drawn far beyond its bird (a generated one in a
    // tiny box) would otherwise print a hundred, one per segment, limit and variant.
    constexpr std::size_t kShown = 8;
    const std::vector<RouteWarning>& all = warnings.value();
    for (std::size_t i = 0; i < all.size() && print;) {
        std::size_t end = i;
        while (end < all.size() && all[end].flock == all[i].flock) ++end;
        for (std::size_t k = i; k < std::min(end, i + kShown); ++k) std::fprintf(stderr, "kodawari: %s: %s\n", kind, all[k].message.c_str());
        if (end - i > kShown) {
            const FlockSpec& flock = scene.flocks[all[i].flock];
            std::fprintf(stderr, "kodawari: %s: %s: $.flocks[%zu] \"%s\": %zu more like these (%zu in all)\n", kind, scene.path.c_str(),
                         all[i].flock, flock.name.c_str(), end - i - kShown, end - i);
        }
        i = end;
    }
    if (strict && !warnings.value().empty()) {
        if (print) {
            const auto starts = static_cast<std::size_t>(std::count_if(warnings.value().begin(), warnings.value().end(), [](const RouteWarning& w) {
                return w.limit == RouteLimit::StartInside;
            }));
            const std::size_t limits = warnings.value().size() - starts;
            std::string what;
            if (limits > 0) what = std::to_string(limits) + (limits == 1 ? " route limit" : " route limits") + " exceeded";
            if (starts > 0) {
                what += (what.empty() ? "" : ", ") + std::to_string(starts) + (starts == 1 ? " obstacle" : " obstacles") +
                        " with birds inside at the start";
            }
            std::fprintf(stderr, "kodawari: error: %s (--strict%s)\n", what.c_str(),
                         limits > 0 ? "; --fit-routes fits corners, turns, bank jumps and speed changes" : "");
        }
        return kExitBadInput;
    }
    return std::nullopt;
}

bool validation_failed(std::uint32_t messages) {
    if (messages == 0) return false;
    std::fprintf(stderr, "kodawari: error: Vulkan validation reported %u messages\n", messages);
    return true;
}

int exit_code(const Error& error) { return error.kind == Error::Kind::InvalidInput ? kExitBadInput : kExitFailure; }

int report(const Error& error) {
    std::fprintf(stderr, "kodawari: error: %s\n", error.message.c_str());
    return exit_code(error);
}

bool stderr_is_terminal() { return ::isatty(STDERR_FILENO) == 1; }

void progress(const char* what, std::uint64_t done, std::uint64_t total) {
    constexpr int kWidth = 30;
    const int filled = total ? static_cast<int>(kWidth * done / total) : kWidth;
    char bar[kWidth + 1];
    for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
    bar[kWidth] = '\0';
    std::fprintf(stderr, "\r%s [%s] %3d%% %llu/%llu", what, bar, total ? static_cast<int>(100 * done / total) : 100,
                 static_cast<unsigned long long>(done), static_cast<unsigned long long>(total));
    if (done >= total) std::fputc('\n', stderr);
    std::fflush(stderr);
}

std::pair<std::uint32_t, std::uint32_t> parse_image_size(const std::string& option, const std::string& text,
                                                         std::uint32_t max_width, std::uint32_t max_height) {
    unsigned w = 0, h = 0;
    char extra = 0;
    if (std::sscanf(text.c_str(), "%ux%u%c", &w, &h, &extra) != 2 || w < 1 || h < 1 || w > max_width || h > max_height) {
        throw UsageError{option + ": expected WxH in pixels with W in [1, " + std::to_string(max_width) + "] and H in [1, " +
                         std::to_string(max_height) + "]; got \"" + text + "\""};
    }
    return {w, h};
}

std::pair<std::uint32_t, std::uint32_t> image_size(const std::optional<std::string>& text) {
    return text ? parse_image_size("--size", *text, 8192, 8192) : std::pair{1280u, 720u};
}

float parse_real(const std::string& option, const std::string& text) {
    std::size_t used = 0;
    float value = 0.0f;
    try {
        value = std::stof(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used == 0 || used != text.size() || !std::isfinite(value)) {
        throw UsageError{option + ": expected a finite number, got \"" + text + "\""};
    }
    return value;
}

}  // namespace kodawari::cli
