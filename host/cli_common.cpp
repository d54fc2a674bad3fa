#include "cli_common.hpp"

#include "kodawari/gpu_info.hpp"
#include "kodawari/simd.hpp"

#include <cstdio>
#include <unistd.h>

namespace kodawari::cli {

std::optional<std::string> Args::option(const std::string& name) {
    const std::string flag_text = "--" + name;
    for (std::size_t i = 0; i < args_.size(); ++i) {
        if (args_[i] == flag_text) {
            if (i + 1 >= args_.size()) throw UsageError{flag_text + " needs a value"};
            std::string value = args_[i + 1];
            args_.erase(args_.begin() + static_cast<std::ptrdiff_t>(i), args_.begin() + static_cast<std::ptrdiff_t>(i) + 2);
            return value;
        }
        if (args_[i].rfind(flag_text + "=", 0) == 0) {
            std::string value = args_[i].substr(flag_text.size() + 1);
            args_.erase(args_.begin() + static_cast<std::ptrdiff_t>(i));
            return value;
        }
    }
    return std::nullopt;
}

bool Args::flag(const std::string& name) {
    for (std::size_t i = 0; i < args_.size(); ++i) {
        if (args_[i] == "--" + name) {
            args_.erase(args_.begin() + static_cast<std::ptrdiff_t>(i));
            return true;
        }
    }
    return false;
}

std::optional<std::optional<std::string>> Args::flag_or_value(const std::string& name) {
    const std::string flag_text = "--" + name;
    for (std::size_t i = 0; i < args_.size(); ++i) {
        if (args_[i] == flag_text || args_[i].rfind(flag_text + "=", 0) == 0) {
            std::optional<std::string> value;
            if (args_[i].size() > flag_text.size()) value = args_[i].substr(flag_text.size() + 1);
            args_.erase(args_.begin() + static_cast<std::ptrdiff_t>(i));
            return value;
        }
    }
    return std::nullopt;
}

std::optional<std::uint64_t> Args::count(const std::string& name, std::uint64_t min, std::uint64_t max) {
    auto text = option(name);
    if (!text) return std::nullopt;
    std::size_t used = 0;
    unsigned long long value = 0;
    try {
        value = std::stoull(*text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used != text->size() || text->empty() || (*text)[0] == '-' || value < min || value > max) {
        throw UsageError{"--" + name + ": expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) +
                         "], got \"" + *text + "\""};
    }
    return value;
}

std::vector<std::string> Args::positionals() const {
    for (const auto& a : args_) {
        if (a.rfind("--", 0) == 0) throw UsageError{"unknown option " + a};
    }
    return args_;
}

std::string Args::first_word() const {
    for (const auto& a : args_) {
        if (a.rfind("--", 0) != 0) return a;
    }
    return "";
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

BackendChoice read_backend_choice(Args& args) {
    BackendChoice choice;
    if (auto b = args.option("backend")) {
        auto parsed = parse_backend_choice(*b);
        if (!parsed) throw UsageError{"--" + parsed.error().message};
        choice.backend = parsed.value();
    }
    // The environment is read here and only here; the library takes options.
    choice.options.device = env_text("KODAWARI_DEVICE");
    if (auto d = args.option("device")) choice.options.device = *d;
    if (auto t = args.count("threads", 1, 1024)) choice.options.threads = static_cast<unsigned>(*t);
    // The cpu backend's instruction set: --isa, else KODAWARI_ISA, else the widest (the
    // backend factories reject a name this machine cannot run, naming the ones it can).
    choice.options.isa = env_text("KODAWARI_ISA");
    const char* isa_from = "KODAWARI_ISA";
    if (auto isa = args.option("isa")) {
        choice.options.isa = *isa;
        isa_from = "--isa";
    }
    if (!choice.options.isa.empty()) {
        if (auto checked = simd_isa(choice.options.isa); !checked) throw UsageError{std::string(isa_from) + ": " + checked.error().message};
    }
    choice.options.validation = args.flag("validation") || env_flag("KODAWARI_VALIDATION");
    choice.options.force_staging = env_flag("KODAWARI_FORCE_STAGING");
    return choice;
}

Result<std::unique_ptr<Simulation>> make_simulation(Scene scene, const BackendChoice& choice, std::optional<std::uint64_t> frames,
                                                    Shard shard) {
    SimulationOptions options{.backend = choice.backend, .options = choice.options, .shard = shard};
    if (frames) options.frames = static_cast<std::uint32_t>(*frames);
    auto sim = Simulation::create(std::move(scene), options);
    if (sim && !sim.value()->fallback_reason().empty()) {
        std::fprintf(stderr, "kodawari: Vulkan unavailable (%s); running on the CPU\n", sim.value()->fallback_reason().c_str());
    }
    return sim;
}

Result<std::unique_ptr<Simulation>> open_simulation(const std::string& path, const BackendChoice& choice,
                                                    std::optional<std::uint64_t> frames, Shard shard) {
    auto scene = load_scene(path);
    if (!scene) return scene.error();
    return make_simulation(std::move(scene).value(), choice, frames, shard);
}

std::string scene_argument(const std::vector<std::string>& positionals, const char* command) {
    if (positionals.size() > 1) throw UsageError{std::string(command) + " takes one scene file"};
    return positionals.empty() ? std::string(kDefaultScene) : positionals[0];
}

bool validation_failed(std::uint32_t messages) {
    if (messages == 0) return false;
    std::fprintf(stderr, "kodawari: error: Vulkan validation reported %u messages\n", messages);
    return true;
}

int report(const Error& error) {
    std::fprintf(stderr, "kodawari: error: %s\n", error.message.c_str());
    return error.kind == Error::Kind::InvalidInput ? kExitBadInput : kExitFailure;
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

std::pair<std::uint32_t, std::uint32_t> image_size(const std::optional<std::string>& text) {
    if (!text) return {1280u, 720u};
    unsigned w = 0, h = 0;
    char extra = 0;
    if (std::sscanf(text->c_str(), "%ux%u%c", &w, &h, &extra) != 2 || w < 1 || h < 1 || w > 8192 || h > 8192) {
        throw UsageError{"--size: expected WxH in pixels with W and H in [1, 8192], e.g. 1280x720; got \"" + *text + "\""};
    }
    return {w, h};
}

}  // namespace kodawari::cli
