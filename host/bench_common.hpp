#pragma once
// What the benchmarks of `kodawari bench` share across files.

#include <algorithm>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "kodawari/backends/backend.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::cli {

/// `s` as the inside of a JSON string.
[[nodiscard]] std::string json_escape(const std::string& s);

/// Writes a benchmark's JSON atomically and says so; the exit code.
int write_json(const std::string& path, const std::string& text);

// One backend's figures: a rate per repetition (bird-frames, joint-steps or frames per
// second) and what it ran on.
struct Measured {
    std::string backend, device;
    std::string isa;       // the cpu backend's SIMD instruction set, "" for the others
    unsigned threads = 0;  // CPU threads of the cpu kinds, 0 for vulkan (lavapipe has its own)
    std::vector<double> per_second, ms_per_frame;
    // The device's timestamps per frame, one value per repetition; empty when the backend
    // has none (the cpu kinds) or a repetition lacked them.
    std::vector<double> gpu_ms_per_frame;
    bool gpu_timed = true;
    std::uint64_t frames = 0;
    // More members of this result's JSON object, each `,"name":number` (flat: gpu_run.sh's
    // awk reads the file); "" for none.
    std::string extra_json;

    [[nodiscard]] static double median(std::vector<double> v) {
        if (v.empty()) return 0.0;
        std::sort(v.begin(), v.end());
        const std::size_t n = v.size();
        return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    }
    [[nodiscard]] double rate() const { return median(per_second); }
    [[nodiscard]] double min() const { return per_second.empty() ? 0.0 : *std::min_element(per_second.begin(), per_second.end()); }
    [[nodiscard]] double max() const { return per_second.empty() ? 0.0 : *std::max_element(per_second.begin(), per_second.end()); }
    /// The median GPU ms per frame, the same statistic as the wall ms/frame beside it;
    /// < 0 when not measured.
    [[nodiscard]] double gpu_ms() const { return gpu_timed && !gpu_ms_per_frame.empty() ? median(gpu_ms_per_frame) : -1.0; }
};

// A backend the bench did not time and why (a device that cannot run the size, no Vulkan):
// a row of the table and of the JSON's "skipped", so that a result left out says so.
struct Skipped {
    std::string backend, reason;
};
/// Says on stdout that `label` is skipped and why, and records it in `skipped`.
void skip(std::vector<Skipped>& skipped, const std::string& label, const std::string& reason);

// A backend set up and warmed up, and one timed repetition of it: returns the seconds it
// took and adds the GPU milliseconds it measured (or makes them negative).
struct Contender {
    Measured measured;
    std::function<Result<double>(double& gpu_ms)> repetition;
};

// What every benchmark takes: the backend options, the backends to time, how often, where
// the JSON goes.
struct BenchCommon {
    BackendFlags backend;
    std::optional<std::string> backends;
    std::optional<std::uint64_t> repetitions;
    std::optional<std::string> json;
    std::optional<std::string> workgroup_sizes;
    bool kernel_statistics = false;  // --kernel-statistics
};

/// One contender's backend: its kind, its options and its name in the table ("vulkan",
/// or "vulkan/wg128" for each of --workgroup-sizes).
struct BenchVariant {
    BackendKind kind;
    BackendOptions options;
    std::string label;
};
/// The backends to time (read_backends) with `choice`'s options, the vulkan one once per
/// size of --workgroup-sizes: variants a GPU run times side by side. With
/// --kernel-statistics each vulkan variant gets a device of its own that captures its
/// kernels' statistics (BackendOptions::context), which report_results() prints last.
/// A variant added later from these (with_rod_kernels, with_pose_layouts) shares its device.
[[nodiscard]] std::vector<BenchVariant> read_variants(const BenchCommon& o, const BackendChoice& choice);

/// Says on stderr that `option` is ignored, being for the `backend` backend, which the
/// bench does not time.
void warn_ignored(const std::string& option, const char* backend);

/// --backend NAME or --backends LIST: the backends to time (cpu-reference,cpu,vulkan by default).
[[nodiscard]] std::vector<BackendKind> read_backends(const BenchCommon& o);
/// --repetitions: how many timed runs of every backend the medians come from.
[[nodiscard]] std::uint32_t read_repetitions(const BenchCommon& o);
/// The ISA and threads a backend of `kind` runs with (what the table and the JSON say).
void describe(Measured& m, BackendKind kind, const BackendOptions& options);
/// The repetitions, interleaved (repetition r of every backend, then r + 1) so that a
/// noisy machine slows them alike; `work_per_frame` x frames / seconds is the rate.
[[nodiscard]] Result<void> run_repetitions(std::vector<Contender>& contenders, std::uint32_t repetitions,
                                           std::uint64_t frames_per_repetition, double work_per_frame);
/// The table and the --json file, the same shape for every benchmark: each backend's
/// median rate with its min and max, its ratio to cpu-reference and to cpu (medians of the
/// same run), the ISA and the threads. `json_head` opens the JSON object. The backends
/// skipped are rows of the table and the JSON's "skipped" array; when nothing was timed
/// at all the exit code is kExitFailure (the JSON still written, saying why).
int report_results(const std::vector<Contender>& contenders, const std::vector<Skipped>& skipped, const char* unit,
                   std::uint32_t repetitions, const BackendOptions& options, const std::string& json_head,
                   const std::optional<std::string>& json_path);
/// --json FILE checked before anything runs: a name, not "-", in a folder that exists and
/// can be written; a UsageError naming --json otherwise.
void check_json_path(const std::optional<std::string>& json_path);
/// The JSON keys every benchmark's head has: "count" and "frames" (the size and the frames
/// per repetition, whatever the benchmark's own older keys call them).
[[nodiscard]] std::string json_size(std::uint64_t count, std::uint64_t frames);
/// --backends, --repetitions, --json and the backend options, on a bench subcommand.
void add_common(CLI::App& c, BenchCommon& o);

/// Adds `bench flock` to `bench`; `run` runs it once parsed.
CLI::App* add_bench_flock(CLI::App& bench, std::function<int()>& run);

/// Adds `bench view` to `bench`; `run` runs it once parsed.
CLI::App* add_bench_view(CLI::App& bench, std::function<int()>& run);
/// Adds `bench ceilings` to `bench`; `run` runs it once parsed.
CLI::App* add_bench_ceilings(CLI::App& bench, std::function<int()>& run);

}  // namespace kodawari::cli
