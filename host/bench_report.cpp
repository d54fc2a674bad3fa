// What the benchmarks of `kodawari bench` share: the backends and repetitions they take,
// the interleaved repetitions and the table and JSON they report (bench_common.hpp).
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <vector>

#include "bench_common.hpp"
#include "kodawari/core/atomic_file.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/vulkan/compute.hpp"
#include "kodawari/vulkan/gpu_info.hpp"
#include "kodawari/backends/simd.hpp"
#include "kodawari/simulation/simulation.hpp"

#include <sys/stat.h>
#include <unistd.h>

namespace kodawari::cli {

std::string json_escape(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (c == '"' || c == '\\') out += '\\';
        if (static_cast<unsigned char>(c) >= 0x20) out += c;
    }
    return out;
}

// Writes a benchmark's JSON atomically and says so.
int write_json(const std::string& path, const std::string& text) {
    auto file = AtomicFile::open(path);
    if (!file) return report(file.error());
    file.value().write(text);
    if (auto r = file.value().commit(); !r) return report(r.error());
    std::printf("wrote %s\n", path.c_str());
    return kExitOk;
}





std::vector<BackendKind> read_backends(const BenchCommon& o) {
    // --backend NAME, which every other command takes, times that one backend here.
    if (o.backend.backend && o.backends) throw UsageError{"--backend and --backends exclude each other: give one"};
    if (o.backend.backend && *o.backend.backend == "auto") {
        throw UsageError{"--backend: bench times named backends (cpu-reference, cpu, vulkan), not auto"};
    }
    const char* option = o.backend.backend ? "--backend" : "--backends";
    const std::string list = o.backend.backend ? *o.backend.backend : o.backends.value_or("cpu-reference,cpu,vulkan");
    if (list.empty()) throw UsageError{std::string(option) + ": expected one or more of cpu-reference, cpu, vulkan, got an empty list"};
    std::vector<BackendKind> kinds;
    std::stringstream names(list);
    for (std::string name; std::getline(names, name, ',');) {
        auto kind = parse_backend_choice(name);
        if (!kind || !kind.value()) {
            throw UsageError{std::string(option) + ": unknown backend \"" + name + "\" (bench times cpu-reference, cpu, vulkan)"};
        }
        // A backend named twice is timed once, as a size named twice in --workgroup-sizes.
        if (std::find(kinds.begin(), kinds.end(), *kind.value()) == kinds.end()) kinds.push_back(*kind.value());
    }
    return kinds;
}

void check_json_path(const std::optional<std::string>& json_path) {
    if (!json_path) return;
    const std::string& path = *json_path;
    if (path.empty()) throw UsageError{"--json: expected a file name, got an empty one"};
    if (path == "-") {
        throw UsageError{"--json: \"-\" is not taken: the table goes to stdout; give a file (/dev/stdout writes the JSON there "
                         "after the table)"};
    }
    struct stat existing {};
    if (::stat(path.c_str(), &existing) == 0) {
        if (S_ISDIR(existing.st_mode)) throw UsageError{"--json: " + path + " is a folder: give a file in it"};
        if (S_ISCHR(existing.st_mode) || S_ISFIFO(existing.st_mode)) return;  // /dev/stdout, /dev/null, a pipe
    }
    const std::string folder = std::filesystem::path(path).parent_path().string();
    const std::string dir = folder.empty() ? "." : folder;
    if (::stat(dir.c_str(), &existing) != 0 || !S_ISDIR(existing.st_mode)) {
        throw UsageError{"--json: " + path + ": the folder " + dir + " does not exist (bench makes no folders): make it first"};
    }
    if (::access(dir.c_str(), W_OK | X_OK) != 0) {
        throw UsageError{"--json: " + path + ": the folder " + dir + " cannot be written (" + std::strerror(errno) + ")"};
    }
}

std::string json_size(std::uint64_t count, std::uint64_t frames) {
    return ",\"count\":" + std::to_string(count) + ",\"frames\":" + std::to_string(frames);
}

void skip(std::vector<Skipped>& skipped, const std::string& label, const std::string& reason) {
    std::printf("  %-14s skipped: %s\n", label.c_str(), reason.c_str());
    std::fflush(stdout);
    skipped.push_back({label, reason});
}

namespace {

// The devices of --kernel-statistics, by the label of the variant that opened them.
std::vector<std::pair<std::string, std::shared_ptr<compute::Device>>>& statistics_devices() {
    static std::vector<std::pair<std::string, std::shared_ptr<compute::Device>>> devices;
    return devices;
}

// --kernel-statistics: each device's kernels as the driver describes them.
void print_kernel_statistics() {
    for (const auto& [label, device] : statistics_devices()) {
        auto statistics = device->kernel_statistics();
        if (!statistics) {
            std::printf("kernel statistics of %s: none (%s)\n", label.c_str(), statistics.error().message.c_str());
            continue;
        }
        std::printf("kernel statistics of %s on %s (VK_KHR_pipeline_executable_properties; the driver's names):\n", label.c_str(),
                    device->info().name.c_str());
        for (const compute::KernelStatistics& k : statistics.value()) {
            std::string spec;
            for (const std::uint32_t s : k.specialization) spec += (spec.empty() ? "" : " ") + std::to_string(s);
            std::printf("  %s [%s]%s%s\n", k.kernel.c_str(), spec.c_str(), k.note.empty() ? "" : ": ", k.note.c_str());
            for (const compute::KernelStatistics::Value& v : k.values) {
                std::printf("    %s: %s = %s\n", v.executable.c_str(), v.name.c_str(), v.value.c_str());
            }
        }
    }
    std::fflush(stdout);
}

}  // namespace

void warn_ignored(const std::string& option, const char* backend) {
    std::fprintf(stderr, "kodawari: warning: %s is ignored: it is for the %s backend, which this bench does not time\n",
                 option.c_str(), backend);
}

namespace {

// A device named (--device, else KODAWARI_DEVICE) that matches none: a UsageError before
// anything runs, as `run` exits 2 for it, rather than the vulkan backend skipped.
void check_named_device(const BackendFlags& flags, const BackendChoice& choice) {
    const std::string& request = choice.options.device;
    if (request.empty()) return;
    // Without a Vulkan loader or driver there is nothing to match: the vulkan backend is
    // then skipped with that reason, as with no device named.
    auto inventory = list_gpus(request);
    if (!inventory || inventory.value().chosen >= 0) return;
    const std::string named = flags.device ? "--device " + request : "KODAWARI_DEVICE=" + request;
    throw UsageError{named + ": " + inventory.value().reason};
}

}  // namespace

std::vector<BenchVariant> read_variants(const BenchCommon& o, const BackendChoice& choice) {
    std::vector<unsigned> sizes;
    if (o.workgroup_sizes) {
        if (o.backend.workgroup_size) throw UsageError{"--workgroup-size and --workgroup-sizes exclude each other: give one"};
        std::stringstream list(*o.workgroup_sizes);
        for (std::string item; std::getline(list, item, ',');) {
            char* end = nullptr;
            const unsigned long n = std::strtoul(item.c_str(), &end, 10);
            if (item.empty() || end == nullptr || *end != '\0' || !compute::is_workgroup_size(n)) {
                throw UsageError{"--workgroup-sizes: \"" + item + "\" is not a power of two from 32 to 1024"};
            }
            // A size named twice is timed once.
            if (std::find(sizes.begin(), sizes.end(), n) == sizes.end()) sizes.push_back(static_cast<unsigned>(n));
        }
    }
    const std::vector<BackendKind> kinds = read_backends(o);
    const bool vulkan = std::find(kinds.begin(), kinds.end(), BackendKind::Vulkan) != kinds.end();
    const bool cpu = std::find(kinds.begin(), kinds.end(), BackendKind::Cpu) != kinds.end();
    if (vulkan) {
        check_named_device(o.backend, choice);
    } else {
        for (const auto& [given, name] : {std::pair{o.workgroup_sizes.has_value(), "--workgroup-sizes"},
                                          std::pair{o.backend.workgroup_size.has_value(), "--workgroup-size"},
                                          std::pair{o.kernel_statistics, "--kernel-statistics"},
                                          std::pair{o.backend.device.has_value(), "--device"}}) {
            if (given) warn_ignored(name, "vulkan");
        }
    }
    if (!cpu) {
        if (o.backend.threads) warn_ignored("--threads", "cpu");
        if (o.backend.isa) warn_ignored("--isa", "cpu");
    }
    std::vector<BenchVariant> variants;
    for (const BackendKind kind : kinds) {
        const std::string name(backend_name(kind));
        if (kind != BackendKind::Vulkan || sizes.empty()) {
            variants.push_back({kind, choice.options, name});
            continue;
        }
        for (const unsigned n : sizes) {
            BackendOptions options = choice.options;
            options.workgroup_size = n;
            variants.push_back({kind, options, name + "/wg" + std::to_string(n)});
        }
    }
    if (o.kernel_statistics) {
        for (BenchVariant& v : variants) {
            if (v.kind != BackendKind::Vulkan) continue;
            v.options.kernel_statistics = true;
            auto device = open_shared_device(v.options);
            if (!device) continue;  // the backend's own attempt reports why
            v.options.context = device.value();
            statistics_devices().push_back({v.label, std::move(device).value()});
        }
    }
    return variants;
}



// --repetitions: how many timed runs of every backend the medians come from.
std::uint32_t read_repetitions(const BenchCommon& o) { return static_cast<std::uint32_t>(o.repetitions.value_or(3)); }

// The ISA and threads a backend of `kind` runs with (what the table and the JSON say).
void describe(Measured& m, BackendKind kind, const BackendOptions& options) {
    if (kind == BackendKind::Cpu) {
        auto isa = simd_isa(options.isa);
        m.isa = isa ? isa.value() : "";
        m.threads = cpu_backend_threads(options);
    } else if (kind == BackendKind::CpuReference) {
        m.threads = 1;
    }
}

// The repetitions, interleaved (repetition r of every backend, then r + 1) so that a
// noisy machine slows them alike.
Result<void> run_repetitions(std::vector<Contender>& contenders, std::uint32_t repetitions, std::uint64_t frames_per_repetition,
                             double work_per_frame) {
    for (std::uint32_t r = 0; r < repetitions; ++r) {
        for (Contender& c : contenders) {
            double gpu_ms = 0.0;
            auto seconds = c.repetition(gpu_ms);
            if (!seconds) return seconds.error();
            Measured& m = c.measured;
            m.per_second.push_back(work_per_frame * static_cast<double>(frames_per_repetition) / seconds.value());
            m.ms_per_frame.push_back(1e3 * seconds.value() / static_cast<double>(frames_per_repetition));
            if (gpu_ms < 0.0) m.gpu_timed = false;
            m.gpu_ms_per_frame.push_back(gpu_ms / static_cast<double>(frames_per_repetition));
            m.frames += frames_per_repetition;
        }
    }
    for (const Contender& c : contenders) {
        std::printf("  %-14s done: %.4g (min %.4g, max %.4g)\n", c.measured.backend.c_str(), c.measured.rate(), c.measured.min(),
                    c.measured.max());
    }
    std::fflush(stdout);
    return {};
}


// The table and the --json file, the same shape for every benchmark: each backend's median
// rate with its min and max over the repetitions, its ratio to cpu-reference and to cpu
// (medians of the same run), the ISA and the threads.
int report_results(const std::vector<Contender>& contenders, const std::vector<Skipped>& skipped, const char* unit,
                   std::uint32_t repetitions, const BackendOptions& options, const std::string& json_head,
                   const std::optional<std::string>& json_path) {
    double reference = 0.0, cpu = 0.0;
    for (const auto& c : contenders) {
        if (c.measured.backend == "cpu-reference") reference = c.measured.rate();
        if (c.measured.backend == "cpu") cpu = c.measured.rate();
    }
    auto ratio = [](double value, double base) {
        char text[32] = "-";
        if (base > 0.0) std::snprintf(text, sizeof text, "%.2fx", value / base);
        return std::string(text);
    };
    auto isa = simd_isa(options.isa);
    const std::string cpu_isa = isa ? isa.value() : "";
    const unsigned cpu_threads = cpu_backend_threads(options);
    // The cpu backend's ISA and threads, where it was timed.
    const bool cpu_timed = std::any_of(contenders.begin(), contenders.end(), [](const Contender& c) { return c.measured.backend == "cpu"; });
    std::printf("\nmedians of %u repetitions (min and max beside them), after warm-up", repetitions);
    if (cpu_timed) std::printf("; cpu: %s, %u threads", cpu_isa.c_str(), cpu_threads);
    std::printf("\n");
    // The backend column fits the longest name ("vulkan/wg128/host-in" with --workgroup-sizes).
    int width = 14;
    for (const auto& c : contenders) width = std::max(width, static_cast<int>(c.measured.backend.size()));
    for (const auto& s : skipped) width = std::max(width, static_cast<int>(s.backend.size()));
    std::printf("%-*s %-36s %14s %11s %11s %10s %12s %9s %7s %-7s %7s\n", width, "backend", "device", unit, "min", "max", "ms/frame",
                "GPU ms/frame", "vs c-ref", "vs cpu", "isa", "threads");
    bool gpu_above_wall = false;
    for (const auto& c : contenders) {
        const Measured& m = c.measured;
        char gpu[32] = "-";
        if (m.gpu_ms() >= 0.0) std::snprintf(gpu, sizeof gpu, "%.3f", m.gpu_ms());
        if (m.gpu_ms() > Measured::median(m.ms_per_frame)) gpu_above_wall = true;
        std::printf("%-*s %-36s %14.4g %11.4g %11.4g %10.3f %12s %9s %7s %-7s %7s\n", width, m.backend.c_str(), m.device.c_str(), m.rate(),
                    m.min(), m.max(), Measured::median(m.ms_per_frame), gpu, ratio(m.rate(), reference).c_str(),
                    ratio(m.rate(), cpu).c_str(), m.isa.empty() ? "-" : m.isa.c_str(),
                    m.threads == 0 ? "-" : std::to_string(m.threads).c_str());
    }
    for (const Skipped& s : skipped) std::printf("%-*s skipped: %s\n", width, s.backend.c_str(), s.reason.c_str());
    std::printf("(ms/frame: wall time per frame; GPU ms/frame: the device's timestamps around the frame's dispatches, "
                "host preparation and waiting left out, '-' without timestamps; both medians of the repetitions)\n");
    // The timestamps bracket the dispatches alone, so they cannot exceed the wall time of
    // the same frames unless the device's clock disagrees with the host's (lavapipe's
    // timestamps are the CPU's clock, read by its own threads).
    if (gpu_above_wall) std::printf("note: GPU time above wall time: the device's timestamp clock disagrees with the host's\n");
    print_kernel_statistics();
    // A bench that timed nothing (every backend skipped) has no result to report.
    int status = kExitOk;
    if (contenders.empty()) {
        std::fprintf(stderr, "kodawari: error: nothing was timed: every backend was skipped (the table says why)\n");
        status = kExitFailure;
    }
    if (!json_path) return status;
    std::string text = json_head + ",\"isa\":\"" + json_escape(cpu_isa) + "\",\"threads\":" + std::to_string(cpu_threads) +
                       ",\"repetitions\":" + std::to_string(repetitions) + ",\"results\":[";
    for (std::size_t i = 0; i < contenders.size(); ++i) {
        const Measured& m = contenders[i].measured;
        char numbers[320];
        std::snprintf(numbers, sizeof numbers,
                      "\"per_second\":%.6g,\"min\":%.6g,\"max\":%.6g,\"ms_per_frame\":%.6g,\"gpu_ms_per_frame\":%s,"
                      "\"vs_cpu_reference\":%s,\"vs_cpu\":%s",
                      m.rate(), m.min(), m.max(), Measured::median(m.ms_per_frame),
                      m.gpu_ms() >= 0.0 ? std::to_string(m.gpu_ms()).c_str() : "null",
                      reference > 0.0 ? std::to_string(m.rate() / reference).c_str() : "null",
                      cpu > 0.0 ? std::to_string(m.rate() / cpu).c_str() : "null");
        text += (i ? "," : "") + std::string("{\"backend\":\"") + m.backend + "\",\"device\":\"" + json_escape(m.device) + "\"," +
                numbers + ",\"isa\":" + (m.isa.empty() ? "null" : "\"" + m.isa + "\"") +
                ",\"threads\":" + (m.threads == 0 ? "null" : std::to_string(m.threads)) + m.extra_json + "}";
    }
    text += "],\"skipped\":[";
    for (std::size_t i = 0; i < skipped.size(); ++i) {
        text += (i ? "," : "") + std::string("{\"backend\":\"") + json_escape(skipped[i].backend) + "\",\"reason\":\"" +
                json_escape(skipped[i].reason) + "\"}";
    }
    text += "]}\n";
    const int written = write_json(*json_path, text);
    return status != kExitOk ? status : written;
}

void add_common(CLI::App& c, BenchCommon& o) {
    add_text(c, "--backends", o.backends, "LIST",
             "the backends to time, comma-separated, of cpu-reference, cpu and vulkan (not auto); one named twice is timed "
             "once (default: cpu-reference,cpu,vulkan)");
    add_count(c, "--repetitions", o.repetitions, 3, 1000, "timed runs of every backend, interleaved, 3 to 1000 (default: 3)");
    add_text(c, "--json", o.json, "FILE.json",
             "also write the results as JSON, to a file in a folder that exists (checked before anything runs; \"-\" is "
             "refused, /dev/stdout writes it after the table; default: none)");
    add_text(c, "--workgroup-sizes", o.workgroup_sizes, "LIST",
             "time the vulkan backend at each of these workgroup sizes, side by side, e.g. 32,64,128,256; a size named "
             "twice is timed once (default: "
             "--workgroup-size, else 64)");
    add_switch(c, "--kernel-statistics", o.kernel_statistics,
               "after the table, each vulkan kernel's statistics as the driver reports them (registers, spills, shared "
               "memory; VK_KHR_pipeline_executable_properties, where the driver offers it; default: off)");
    add_backend_options(c, o.backend);
    c.get_option("--backend")
        ->description("time this one backend, as --backends NAME (not auto; default: the --backends list)")
        ->type_name("vulkan|cpu|cpu-reference");
    c.get_option("--threads")->description("the cpu backend's threads (default: one per hardware thread)");
}


}  // namespace kodawari::cli
