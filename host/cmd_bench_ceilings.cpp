// `kodawari bench ceilings`: the machine's fp32 and memory ceilings (measure_ceilings(),
// kodawari/backends/simd.hpp), measured by this binary, so that the other benchmarks'
// rates can be set against them from the same session (docs/performance.md).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "bench_common.hpp"
#include "kodawari/backends/simd.hpp"

namespace kodawari::cli {
namespace {

struct CeilingsOptions {
    std::optional<std::uint64_t> threads;
    std::optional<std::string> isa;
    std::optional<std::uint64_t> repetitions;
    std::optional<std::uint64_t> triad_mib;
    std::optional<std::string> json;
};

struct Spread {
    double median = 0.0, min = 0.0, max = 0.0;
};

// The other benchmarks' statistics (Measured: the median of an even count is the mean of
// the middle two).
Spread spread(const std::vector<double>& v) {
    return {Measured::median(v), *std::min_element(v.begin(), v.end()), *std::max_element(v.begin(), v.end())};
}

int bench_ceilings(const CeilingsOptions& o) {
    check_json_path(o.json);
    const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
    const auto threads = static_cast<unsigned>(o.threads.value_or(hardware));
    std::string isa = o.isa.value_or("");
    if (!o.isa) {
        if (const char* env = std::getenv("KODAWARI_ISA")) isa = env;
    }
    const auto repetitions = static_cast<std::uint32_t>(o.repetitions.value_or(5));
    const std::size_t bytes = static_cast<std::size_t>(o.triad_mib.value_or(384)) << 20;
    std::vector<double> flops, triad;
    MachineCeilings last;
    for (std::uint32_t r = 0; r < repetitions; ++r) {
        auto measured = measure_ceilings(isa, threads, bytes);
        if (!measured) {
            std::string message = measured.error().message;
            // The arguments' names as the command spells them.
            for (const auto& [api, flag] : {std::pair{"measure_ceilings: isa: ", o.isa ? "--isa: " : "KODAWARI_ISA: "},
                                            std::pair{"measure_ceilings: threads: ", "--threads: "}}) {
                if (message.rfind(api, 0) == 0) message = flag + message.substr(std::string(api).size());
            }
            if (measured.error().kind == Error::Kind::InvalidInput) throw UsageError{message};
            return report(make_error(measured.error().kind, message));
        }
        last = measured.value();
        flops.push_back(last.fp32_flops);
        triad.push_back(last.triad_bytes_per_second);
    }
    const Spread f = spread(flops), t = spread(triad);
    std::printf("bench ceilings: fp32 fused multiply-adds (12 independent chains of one vector a thread, FMA counted as 2 "
                "flops) and STREAM's triad over %zu MiB (12 bytes an element), %u repetitions, %s, %u threads\n",
                last.triad_bytes >> 20, repetitions, last.isa.c_str(), last.threads);
    std::printf("%-22s %12s %12s %12s\n", "ceiling", "median", "min", "max");
    std::printf("%-22s %12.1f %12.1f %12.1f\n", "fp32 GFLOP/s", f.median * 1e-9, f.min * 1e-9, f.max * 1e-9);
    std::printf("%-22s %12.2f %12.2f %12.2f\n", "triad GB/s", t.median * 1e-9, t.min * 1e-9, t.max * 1e-9);
    if (!o.json) return kExitOk;
    char text[600];
    std::snprintf(text, sizeof text,
                  "{\"benchmark\":\"ceilings\",\"isa\":\"%s\",\"threads\":%u,\"repetitions\":%u,\"triad_bytes\":%zu,"
                  "\"fp32_flops\":{\"median\":%.6g,\"min\":%.6g,\"max\":%.6g},"
                  "\"triad_bytes_per_second\":{\"median\":%.6g,\"min\":%.6g,\"max\":%.6g}}\n",
                  last.isa.c_str(), last.threads, repetitions, last.triad_bytes, f.median, f.min, f.max, t.median, t.min, t.max);
    return write_json(*o.json, text);
}

}  // namespace

CLI::App* add_bench_ceilings(CLI::App& bench, std::function<int()>& run) {
    auto ceilings = std::make_shared<CeilingsOptions>();
    CLI::App* c = bench.add_subcommand("ceilings", "the machine's fp32 peak (fused multiply-adds) and memory rate (STREAM "
                                                   "triad), the ceilings the other benchmarks are set against");
    add_count(*c, "--threads", ceilings->threads, 1, 1024, "threads, 1 to 1024 (default: one per hardware thread)");
    add_text(*c, "--isa", ceilings->isa, "avx512|avx2|sse4|scalar",
             "the fp32 loop's SIMD instruction set (default: $KODAWARI_ISA, else the widest this CPU runs)");
    add_count(*c, "--repetitions", ceilings->repetitions, 1, 1000, "measurements, 1 to 1000 (default: 5)");
    add_count(*c, "--triad-mib", ceilings->triad_mib, 3, 65536, "the triad's three arrays together, in MiB, 3 to 65536 "
                                                                "(default: 384, far past the caches)");
    add_text(*c, "--json", ceilings->json, "FILE.json",
             "also write the results as JSON, to a file in a folder that exists (checked before anything runs; default: none)");
    c->footer("Rows: the fp32 rate (12 independent chains of fused multiply-adds of one vector on every thread: no memory, "
              "past every FMA pipe's latency; without FMA instructions, as on sse4, a multiply and an add) and the triad "
              "a[i] = b[i] + s c[i] (two reads and a write counted, the best of three passes), each the median of the "
              "repetitions with min and max. --json writes the same (isa, threads, repetitions, triad_bytes, fp32_flops and "
              "triad_bytes_per_second with median, min, max); docs/performance.md.");
    run = [ceilings] { return bench_ceilings(*ceilings); };
    return c;
}

}  // namespace kodawari::cli
