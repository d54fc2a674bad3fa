#pragma once
// Helpers shared by the test suites.

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <string>
#include <system_error>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "kodawari/backends/backend.hpp"
#include "kodawari/vulkan/gpu_info.hpp"
#include "kodawari/backends/simd.hpp"
#include "test_paths.hpp"

namespace kodawari::testing_support {

/// A fresh directory per test (named after it and the process), removed with everything
/// in it at the end of the test.
class TempDir {
public:
    TempDir() {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        path_ = std::filesystem::temp_directory_path() /
                ("kodawari_" + std::string(info->test_suite_name()) + "_" + info->name() + "_" + std::to_string(::getpid()));
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ignored;
        std::filesystem::remove_all(path_, ignored);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    [[nodiscard]] const std::filesystem::path& path() const { return path_; }
    [[nodiscard]] std::string file(const std::string& name) const { return (path_ / name).string(); }
    /// The names of what the directory holds (to check that no temporary file is left).
    [[nodiscard]] std::vector<std::string> entries() const {
        std::vector<std::string> names;
        for (const auto& entry : std::filesystem::directory_iterator(path_)) names.push_back(entry.path().filename().string());
        return names;
    }

private:
    std::filesystem::path path_;
};

/// The bytes of the file at `path` ("" when it cannot be read).
inline std::string file_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) return {};
    std::string data(static_cast<std::size_t>(in.tellg()), '\0');
    in.seekg(0);
    in.read(data.data(), static_cast<std::streamsize>(data.size()));
    return data;
}

/// The options of the GPU tests' devices: validation (with synchronization validation)
/// when ctest sets KODAWARI_VALIDATION=1. The library reads no environment variable;
/// the tests, like the `kodawari` command, pass what the environment says.
/// Where the validation layer is not installed (a bare GPU machine), the tests run without
/// it and say so once, rather than failing every Vulkan test as unsupported.
inline bool validation_requested() {
    const char* value = std::getenv("KODAWARI_VALIDATION");
    const bool asked = value != nullptr && std::string(value) != "" && std::string(value) != "0";
    if (!asked) return false;
    static const bool available = [] {
        const bool found = vulkan_validation_available();
        if (!found) {
            std::fprintf(stderr, "KODAWARI_VALIDATION=1, but VK_LAYER_KHRONOS_validation is not installed: the Vulkan "
                                 "tests run without validation\n");
        }
        return found;
    }();
    return available;
}
inline BackendOptions gpu_options() {
    BackendOptions options;
    options.validation = validation_requested();
    return options;
}

/// One configuration of the shared backend test bodies: a backend kind and, for the cpu
/// backend, the SIMD instruction set it is made with (BackendOptions::isa). Converts to
/// its kind, so that a body asks `GetParam() == BackendKind::Vulkan`.
struct BackendCase {
    BackendKind kind = BackendKind::CpuReference;
    std::string isa;
    // NOLINTNEXTLINE(google-explicit-constructor): the bodies compare the case with kinds
    operator BackendKind() const { return kind; }
};
/// "cpu-reference", "cpu/avx512", "vulkan": what the measured lines of the bodies say.
inline std::string case_name(const BackendCase& c) {
    return std::string(backend_name(c.kind)) + (c.isa.empty() ? "" : "/") + c.isa;
}
inline void PrintTo(const BackendCase& c, std::ostream* os) { *os << case_name(c); }

/// The options of a case's backends: gpu_options() with the case's instruction set.
inline BackendOptions backend_options(const BackendCase& c) {
    BackendOptions options = gpu_options();
    options.isa = c.isa;
    return options;
}

/// Every backend configuration, for the suites that run one body per backend
/// (INSTANTIATE_TEST_SUITE_P(All, Suite, all_backend_kinds(), backend_test_name)):
/// cpu-reference, the cpu backend at every instruction set this machine runs (so at least
/// two: the widest and Highway's scalar fallback; on this project's machines avx512,
/// avx2, sse4 and scalar, i.e. 16, 8, 4 and 1 lanes), and vulkan.
inline std::vector<BackendCase> backend_cases() {
    std::vector<BackendCase> cases{{BackendKind::CpuReference, ""}};
    for (const std::string& isa : available_simd_isas()) cases.push_back({BackendKind::Cpu, isa});
    cases.push_back({BackendKind::Vulkan, ""});
    return cases;
}
inline auto all_backend_kinds() { return ::testing::ValuesIn(backend_cases()); }
/// The configuration as a test name: "cpu_reference", "cpu_avx512", "cpu_sse4", "vulkan".
inline std::string backend_test_name(const ::testing::TestParamInfo<BackendCase>& info) {
    std::string name(backend_name(info.param.kind));
    if (!info.param.isa.empty()) name += "_" + info.param.isa;
    for (char& c : name) {
        if (c == '-') c = '_';
    }
    return name;
}

/// Why the GPU tests cannot run here ("" when a Vulkan device exists). The GPU tests skip
/// only when there is no Vulkan device at all, and say why; any other failure fails.
inline std::string no_vulkan_device_reason() {
    auto gpus = list_gpus("");
    if (gpus.ok() && !gpus.value().devices.empty()) return "";
    return "no Vulkan device on this machine (" + (gpus.ok() ? gpus.value().reason : gpus.error().message) +
           "); the GPU tests need one";
}

/// The device list_gpus("") chooses, as the tests that depend on its type or limits need
/// it: fills `out` and returns "", or returns why there is none.
inline std::string chosen_device(GpuDeviceInfo& out) {
    auto gpus = list_gpus("");
    if (!gpus.ok()) return gpus.error().message;
    if (gpus.value().chosen < 0) return gpus.value().reason;
    out = gpus.value().devices[static_cast<std::size_t>(gpus.value().chosen)];
    return "";
}

/// Runs a command through the shell, returns its exit status (-1 when it did not exit)
/// and appends its output, stdout and stderr together, to `output`.
inline int run_command(const std::string& command, std::string& output) {
    std::FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
    if (pipe == nullptr) return -1;
    std::array<char, 4096> chunk{};
    std::size_t read = 0;
    while ((read = std::fread(chunk.data(), 1, chunk.size(), pipe)) > 0) output.append(chunk.data(), read);
    const int status = ::pclose(pipe);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// `text` as one single-quoted shell word.
inline std::string shell_quote(const std::string& text) {
    std::string quoted = "'";
    for (const char c : text) {
        if (c == '\'') {
            quoted += "'\\''";
        } else {
            quoted += c;
        }
    }
    return quoted + "'";
}

/// The shell command that runs glTF-Validator (tests/tools/validate_gltf.mjs, the npm
/// package scripts/setup installs) on `path`; it prints "glTF-Validator: N errors, M
/// warnings, ..." and the first issues.
inline std::string gltf_validator_command(const std::string& path) {
    return "KODAWARI_NODE_TOOLS=" + shell_quote(KODAWARI_NODE_TOOLS) + " node " +
           shell_quote(std::string(KODAWARI_SOURCE_DIR) + "/tests/tools/validate_gltf.mjs") + " --max-issues 20 " +
           shell_quote(path);
}

/// Imports `path` with Blender's own glTF importer (tests/tools/blender_check.py) and
/// returns the JSON line it reports ({"check": "kodawari-blender", ...}), or "" when the
/// import failed or printed no report; `output` holds everything Blender printed.
inline std::string blender_report_line(const std::string& path, std::string& output) {
    output.clear();
    const std::string command = "blender -b --factory-startup --python-exit-code 1 -P " +
                                shell_quote(std::string(KODAWARI_SOURCE_DIR) + "/tests/tools/blender_check.py") + " -- " +
                                shell_quote(path);
    if (run_command(command, output) != 0) return "";
    std::string report;
    std::size_t start = 0;
    while (start < output.size()) {
        std::size_t end = output.find('\n', start);
        if (end == std::string::npos) end = output.size();
        const std::string line = output.substr(start, end - start);
        if (line.rfind("{\"check\": \"kodawari-blender\"", 0) == 0) report = line;
        start = end + 1;
    }
    return report;
}

/// Base64 (RFC 4648, with padding), for the data URIs of glTF files written by tests.
inline std::string base64(const std::vector<unsigned char>& bytes) {
    static const char* kDigits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (std::size_t i = 0; i < bytes.size(); i += 3) {
        const std::uint32_t b0 = bytes[i];
        const std::uint32_t b1 = i + 1 < bytes.size() ? bytes[i + 1] : 0u;
        const std::uint32_t b2 = i + 2 < bytes.size() ? bytes[i + 2] : 0u;
        const std::uint32_t v = (b0 << 16) | (b1 << 8) | b2;
        out += kDigits[(v >> 18) & 63];
        out += kDigits[(v >> 12) & 63];
        out += i + 1 < bytes.size() ? kDigits[(v >> 6) & 63] : '=';
        out += i + 2 < bytes.size() ? kDigits[v & 63] : '=';
    }
    return out;
}

}  // namespace kodawari::testing_support
