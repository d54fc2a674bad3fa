// The C API's shared parts: version, status names, the last-error messages, the argument
// checks, and the mapping of engine errors to status codes.
#include "capi/capi_common.hpp"
#include "kodawari/vulkan/compute.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"

#include <algorithm>
#include <vector>
#include <string_view>
#include <array>
#include <charconv>
#include <cmath>

#include "kodawari/domains/flocking.hpp"
#include "kodawari/backends/simd.hpp"
#include "kodawari/core/version.hpp"

namespace kodawari::capi {
namespace {

// This thread's message of its last call (kodawari.h: valid until the thread's next call).
thread_local std::string t_last_error;

// Vulkan's VkResult codes for running out of memory (the engine keeps them in
// Error::vk_result as ints so that its headers name no Vulkan type).
constexpr int kVkErrorOutOfHostMemory = -1;
constexpr int kVkErrorOutOfDeviceMemory = -2;

bool finite(float v) { return std::isfinite(v); }

std::string vector_text(const float* v, std::size_t n) {
    std::string text = "(";
    for (std::size_t i = 0; i < n; ++i) text += (i ? ", " : "") + number(v[i]);
    return text + ")";
}

}  // namespace

const char* last_error_text() noexcept { return t_last_error.c_str(); }

namespace {

// The engine's messages begin with the C++ call that failed ("set_flock_agents: agents[0]
// ...", "Simulation::buffer: ..."): the C function's name takes that place rather than
// going before it, when the two name one call (kodawari_simulation_set_flock_agents and
// set_flock_agents or Simulation::set_flock_agents).
std::string_view without_cxx_name(std::string_view function, std::string_view message) {
    const std::size_t colon = message.find(": ");
    if (colon == std::string_view::npos) return message;
    std::string_view name = message.substr(0, colon);
    if (name.starts_with("Simulation::")) name.remove_prefix(std::string_view("Simulation::").size());
    for (const std::string_view prefix : {std::string_view("kodawari_simulation_"), std::string_view("kodawari_")}) {
        if (!name.empty() && function.starts_with(prefix) && function.substr(prefix.size()) == name) {
            return message.substr(colon + 2);
        }
    }
    return message;
}

}  // namespace

void record(kodawari_status status, const char* function, const std::string& message, std::string* handle_message) noexcept {
    try {
        if (status == KODAWARI_OK) {
            t_last_error.clear();
            if (handle_message != nullptr) handle_message->clear();
            return;
        }
        t_last_error = std::string(function) + ": " + std::string(without_cxx_name(function, message));
        if (handle_message != nullptr) *handle_message = t_last_error;
    } catch (...) {
        // No memory left for the message: the status still says what happened, and an
        // empty message is better than a partial one.
        t_last_error.clear();
        if (handle_message != nullptr) handle_message->clear();
    }
}

void reject(kodawari_status status, std::string message) { throw Rejection{status, std::move(message)}; }

void invalid(const std::string& what, const std::string& problem) {
    reject(KODAWARI_INVALID_ARGUMENT, what + ": " + problem);
}

void fail(const Error& error) {
    kodawari_status status = KODAWARI_INTERNAL;
    switch (error.kind) {
        case Error::Kind::InvalidInput: status = KODAWARI_INVALID_ARGUMENT; break;
        case Error::Kind::Unsupported: status = KODAWARI_UNAVAILABLE; break;
        case Error::Kind::Vulkan:
            status = error.vk_result == kVkErrorOutOfHostMemory || error.vk_result == kVkErrorOutOfDeviceMemory
                         ? KODAWARI_OUT_OF_MEMORY
                         : KODAWARI_DEVICE_ERROR;
            break;
        case Error::Kind::Io:
        case Error::Kind::Internal: status = KODAWARI_INTERNAL; break;
    }
    reject(status, error.message);
}

std::string number(double value) {
    if (std::isnan(value)) return "nan";
    if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
    std::array<char, 32> buffer{};
    // As a float: the caller's value was one, and its shortest text is what they wrote.
    const auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), static_cast<float>(value));
    return ec == std::errc() ? std::string(buffer.data(), end) : std::to_string(value);
}

std::string at(const std::string& base, std::size_t index) { return base + "[" + std::to_string(index) + "]"; }

void require_pointer(const void* pointer, const std::string& what) {
    if (pointer == nullptr) invalid(what, "is NULL");
}

void require_array(const void* pointer, std::size_t count, const std::string& what, const std::string& count_name) {
    if (pointer == nullptr && count != 0) {
        invalid(what, "is NULL, but " + count_name + " is " + std::to_string(count) + "; expected an array of that many");
    }
}

void require_flag(std::uint32_t value, const std::string& what) {
    if (value > 1) invalid(what, std::to_string(value) + "; expected 0 or 1 (is the struct initialized?)");
}

void require_range(float value, double low, double high, const std::string& what, bool low_open, bool high_open) {
    // Against the bounds as floats: the caller's 0.05f (0.0500000007) is "0.05", and a
    // bound that only the double can hold would turn away the float nearest to it.
    const double v = value;
    const double lo = static_cast<float>(low);
    const double hi = static_cast<float>(high);
    const bool above = low_open ? v > lo : v >= lo;
    const bool below = high_open ? v < hi : v <= hi;
    if (finite(value) && above && below) return;
    invalid(what, number(v) + "; expected a number in " + (low_open ? "(" : "[") + number(low) + ", " + number(high) +
                      (high_open ? ")" : "]"));
}

rods::WindField read_wind(const kodawari_wind& wind, const std::string& what) {
    require_point(wind.velocity, 100.0, what + ".velocity");
    require_range(wind.gust, 0.0, 4.0, what + ".gust");
    require_range(wind.gust_period, 0.05, 1000.0, what + ".gust_period");
    require_range(wind.gust_size, 0.05, 10000.0, what + ".gust_size");
    rods::WindField out;
    out.velocity = glm::vec3(wind.velocity[0], wind.velocity[1], wind.velocity[2]);
    out.gust = wind.gust;
    out.gust_period = wind.gust_period;
    out.gust_size = wind.gust_size;
    out.seed = wind.seed;
    // The engine's own check, behind ours (the float bounds agree with it).
    check(rods::validate(out, what.c_str()));
    return out;
}

kodawari_wind to_c(const rods::WindField& wind) {
    kodawari_wind out{};
    for (int i = 0; i < 3; ++i) out.velocity[i] = wind.velocity[i];
    out.gust = wind.gust;
    out.gust_period = wind.gust_period;
    out.gust_size = wind.gust_size;
    out.seed = wind.seed;
    return out;
}

void require_point(const float* xyz, double limit, const std::string& what) {
    for (std::size_t i = 0; i < 3; ++i) {
        if (!finite(xyz[i]) || std::abs(static_cast<double>(xyz[i])) > limit) {
            invalid(what, vector_text(xyz, 3) + "; expected finite coordinates within " + number(limit) + " m");
        }
    }
}

void require_unit_quat(const float* xyzw, const std::string& what) {
    double length2 = 0.0;
    for (std::size_t i = 0; i < 4; ++i) length2 += static_cast<double>(xyzw[i]) * static_cast<double>(xyzw[i]);
    const double length = std::sqrt(length2);
    if (!(std::abs(length - 1.0) < 1e-3)) {
        invalid(what, vector_text(xyzw, 4) + " has length " + number(length) +
                          "; expected a unit quaternion (x, y, z, w), length within 1e-3 of 1");
    }
}

void require_direction(const float* xyz, const std::string& what) {
    double length2 = 0.0;
    for (std::size_t i = 0; i < 3; ++i) {
        if (!finite(xyz[i]) || std::abs(static_cast<double>(xyz[i])) > 1e6) {
            invalid(what, vector_text(xyz, 3) + "; expected a direction with finite coordinates within 1e6");
        }
        length2 += static_cast<double>(xyz[i]) * static_cast<double>(xyz[i]);
    }
    if (!(std::sqrt(length2) >= 1e-6)) {
        invalid(what, vector_text(xyz, 3) + " is a zero vector; expected a direction (length at least 1e-6)");
    }
}

void require_transform(const kodawari_transform& t, const std::string& what) {
    require_point(t.position, 1e6, what + ".position");
    require_unit_quat(t.rotation, what + ".rotation");
}

void require_capsule(const kodawari_capsule& c, double limit, const std::string& what) {
    require_point(c.a, limit, what + ".a");
    require_point(c.b, limit, what + ".b");
    require_range(c.radius, 0.0, limit, what + ".radius");
}

void require_camera(const kodawari_camera& camera, const std::string& what) {
    require_flag(camera.orthographic, what + ".orthographic");
    require_point(camera.position, 1e6, what + ".position");
    require_direction(camera.forward, what + ".forward");
}

BackendKind backend_kind(kodawari_backend backend) {
    switch (backend) {
        case KODAWARI_BACKEND_CPU_REFERENCE: return BackendKind::CpuReference;
        case KODAWARI_BACKEND_CPU: return BackendKind::Cpu;
        default: return BackendKind::Vulkan;
    }
}

kodawari_backend backend_enum(BackendKind kind) {
    switch (kind) {
        case BackendKind::CpuReference: return KODAWARI_BACKEND_CPU_REFERENCE;
        case BackendKind::Cpu: return KODAWARI_BACKEND_CPU;
        case BackendKind::Vulkan: break;
    }
    return KODAWARI_BACKEND_VULKAN;
}

void require_backend_options(const kodawari_backend_options& options, const std::string& what) {
    const std::int64_t backend = enum_value(options.backend);
    if (backend < KODAWARI_BACKEND_AUTO || backend > KODAWARI_BACKEND_VULKAN) {
        invalid(what + ".backend", std::to_string(backend) +
                                       "; expected KODAWARI_BACKEND_AUTO (0), _CPU_REFERENCE (1), _CPU (2) or _VULKAN (3)");
    }
    require_flag(options.validation, what + ".validation");
    if (options.threads > 1024) {
        invalid(what + ".threads", std::to_string(options.threads) + "; expected 0 (one per hardware thread) to 1024");
    }
    if (options.isa != nullptr && options.isa[0] != '\0') {
        if (backend != KODAWARI_BACKEND_AUTO && backend != KODAWARI_BACKEND_CPU) {
            invalid(what + ".isa", std::string("\"") + options.isa + "\" with a backend other than KODAWARI_BACKEND_CPU, which has no instruction-set choice");
        }
        auto isa = simd_isa(options.isa);
        if (!isa) invalid(what + ".isa", isa.error().message);
    }
    if (options.workgroup_size != 0) {
        if (backend != KODAWARI_BACKEND_AUTO && backend != KODAWARI_BACKEND_VULKAN) {
            invalid(what + ".workgroup_size", std::to_string(options.workgroup_size) +
                                                  " with a backend other than KODAWARI_BACKEND_VULKAN, which has no workgroups");
        }
        if (!compute::is_workgroup_size(options.workgroup_size)) {
            invalid(what + ".workgroup_size",
                    std::to_string(options.workgroup_size) + "; expected 0 (64) or a power of two from 32 to 1024");
        }
    }
    if (options.vulkan_device != nullptr) {
        if (backend != KODAWARI_BACKEND_AUTO && backend != KODAWARI_BACKEND_VULKAN) {
            invalid(what + ".vulkan_device", "set with a CPU backend; the application's device runs KODAWARI_BACKEND_VULKAN");
        }
        if ((options.device != nullptr && options.device[0] != '\0') || options.validation != 0) {
            invalid(what + ".vulkan_device", "set together with device or validation, which are then the application's choice");
        }
    }
}

kodawari_backend effective_backend(const kodawari_backend_options& options) {
    return options.vulkan_device != nullptr ? KODAWARI_BACKEND_VULKAN : options.backend;
}

std::string_view device_buffer(kodawari_device_buffer which) {
    const std::int64_t value = enum_value(which);
    switch (value) {
        case KODAWARI_BUFFER_CHAIN_STATES: return rod_buffers::chain_states;
        case KODAWARI_BUFFER_JOINT_MOTION: return rod_buffers::motion;
        case KODAWARI_BUFFER_JOINT_SPIN: return rod_buffers::spin;
        case KODAWARI_BUFFER_BIRD_POSES: return bird_buffers::poses;
        case KODAWARI_BUFFER_FLOCK_AGENTS: return flock_buffers::agents;
        default: invalid("which", std::to_string(value) + "; expected a kodawari_device_buffer (0 to 4)");
    }
}

kodawari_buffer_range buffer_range(const VulkanBufferRange& range) {
    kodawari_buffer_range r{};
    r.buffer = reinterpret_cast<std::uint64_t>(range.buffer);
    r.offset = range.offset;
    r.range = range.range;
    r.count = range.count;
    r.stride = range.stride;
    return r;
}

void fill_range(const DeviceData* data, kodawari_device_buffer which, kodawari_buffer_range* out, bool chains) {
    require_pointer(out, "out");
    const std::string_view name = device_buffer(which);
    if (name == flock_buffers::agents) invalid("which", "FLOCK_AGENTS is a scene simulation's buffer (kodawari_simulation_buffer)");
    if (chains == (name == bird_buffers::poses)) {
        invalid("which", chains ? "BIRD_POSES is a bird world's buffer" : "a chain world's buffer; a bird world has BIRD_POSES");
    }
    if (data == nullptr) {
        reject(KODAWARI_INVALID_ARGUMENT, "world: not on a Vulkan device (or, for birds, no frame simulated yet); its buffers are on the host");
    }
    auto range = vulkan_buffer(*data, name);
    check(range);
    *out = buffer_range(range.value());
}

BackendOptions backend_options(const kodawari_backend_options& options) {
    BackendOptions out;
    out.device = options.device != nullptr ? options.device : "";
    out.validation = options.validation != 0;
    out.threads = options.threads;
    out.isa = options.isa != nullptr ? options.isa : "";
    out.workgroup_size = options.workgroup_size;
    if (options.vulkan_device != nullptr) out.context = options.vulkan_device->context;
    return out;
}

void copy_text(const std::string& text, char* out, std::size_t size) {
    const std::size_t n = std::min(text.size(), size - 1);
    text.copy(out, n);
    out[n] = '\0';
}

void require_capacity(const void* pointer, std::size_t capacity, std::size_t needed, const std::string& what,
                      const std::string& count_text) {
    if (pointer == nullptr || capacity >= needed) return;
    reject(KODAWARI_BUFFER_TOO_SMALL, what + ": holds " + std::to_string(capacity) + " floats, needs " +
                                          std::to_string(needed) + " (" + count_text + ")");
}

void require_chain_output(const kodawari_chain_output& out, std::size_t joints, std::size_t chains) {
    const std::string j = std::to_string(joints) + " joints";
    const std::string c = std::to_string(chains) + " chains";
    require_capacity(out.positions, out.positions_capacity, joints * 3, "out->positions", j + " x 3");
    require_capacity(out.orientations, out.orientations_capacity, joints * 4, "out->orientations", j + " x 4");
    require_capacity(out.rest_positions, out.rest_positions_capacity, joints * 3, "out->rest_positions", j + " x 3");
    require_capacity(out.view_directions, out.view_directions_capacity, chains * 3, "out->view_directions", c + " x 3");
    require_capacity(out.weights, out.weights_capacity, chains * KODAWARI_WEIGHTS_PER_CHAIN, "out->weights",
                     c + " x KODAWARI_WEIGHTS_PER_CHAIN (" + std::to_string(KODAWARI_WEIGHTS_PER_CHAIN) + ")");
}

void write_chain_output(const ChainSnapshot& s, const kodawari_chain_output& out) {
    const auto copy3 = [](const std::vector<glm::vec3>& from, float* to) {
        if (to == nullptr) return;
        for (std::size_t i = 0; i < from.size(); ++i) {
            to[3 * i] = from[i].x;
            to[3 * i + 1] = from[i].y;
            to[3 * i + 2] = from[i].z;
        }
    };
    copy3(s.positions, out.positions);
    copy3(s.rest, out.rest_positions);
    copy3(s.view_directions, out.view_directions);
    if (out.orientations != nullptr) {
        for (std::size_t i = 0; i < s.orientations.size(); ++i) {
            const glm::quat& q = s.orientations[i];
            float* o = out.orientations + 4 * i;
            o[0] = q.x;
            o[1] = q.y;
            o[2] = q.z;
            o[3] = q.w;
        }
    }
    if (out.weights != nullptr) std::copy(s.weights.begin(), s.weights.end(), out.weights);
}

}  // namespace kodawari::capi

// ---- Version and status: the entry points every other part shares.

using namespace kodawari;

extern "C" {

KODAWARI_C_API const char* kodawari_version(void) {
    // kHeaderVersion is a view of a string literal: terminated.
    return kHeaderVersion.data();
}
KODAWARI_C_API int kodawari_version_major(void) { return KODAWARI_VERSION_MAJOR; }
KODAWARI_C_API int kodawari_version_minor(void) { return KODAWARI_VERSION_MINOR; }
KODAWARI_C_API int kodawari_version_patch(void) { return KODAWARI_VERSION_PATCH; }

KODAWARI_C_API const char* kodawari_status_name(kodawari_status status) {
    switch (capi::enum_value(status)) {
        case KODAWARI_OK: return "KODAWARI_OK";
        case KODAWARI_INVALID_ARGUMENT: return "KODAWARI_INVALID_ARGUMENT";
        case KODAWARI_BUFFER_TOO_SMALL: return "KODAWARI_BUFFER_TOO_SMALL";
        case KODAWARI_UNAVAILABLE: return "KODAWARI_UNAVAILABLE";
        case KODAWARI_DEVICE_ERROR: return "KODAWARI_DEVICE_ERROR";
        case KODAWARI_OUT_OF_MEMORY: return "KODAWARI_OUT_OF_MEMORY";
        case KODAWARI_INTERNAL: return "KODAWARI_INTERNAL";
        case KODAWARI_STATUS_MAX_ENUM: break;
    }
    return "unknown kodawari_status";
}

KODAWARI_C_API const char* kodawari_last_error(void) { return capi::last_error_text(); }

KODAWARI_C_API kodawari_status kodawari_camera_from_view_matrix(const float view[16], uint32_t orthographic,
                                                                kodawari_camera* out) {
    return capi::guard("kodawari_camera_from_view_matrix", nullptr, [&] {
        capi::require_pointer(view, "view");
        capi::require_pointer(out, "out");
        capi::require_flag(orthographic, "orthographic");
        const auto m = [&](int row, int column) { return static_cast<double>(view[column * 4 + row]); };
        for (int i = 0; i < 16; ++i) {
            if (!std::isfinite(view[i]) || std::abs(view[i]) > 1e6f) {
                capi::invalid(capi::at("view", static_cast<std::size_t>(i)),
                              capi::number(view[i]) + "; expected finite elements within 1e6");
            }
        }
        if (m(3, 0) != 0.0 || m(3, 1) != 0.0 || m(3, 2) != 0.0 || m(3, 3) != 1.0) {
            capi::invalid("view", "last row (" + capi::number(m(3, 0)) + ", " + capi::number(m(3, 1)) + ", " +
                                      capi::number(m(3, 2)) + ", " + capi::number(m(3, 3)) +
                                      "); expected (0, 0, 0, 1): a rigid view matrix, not a projection");
        }
        // Rows of the rotation part R (world to camera) must be orthonormal: R R^T = I.
        for (int a = 0; a < 3; ++a) {
            for (int b = 0; b < 3; ++b) {
                const double dot = m(a, 0) * m(b, 0) + m(a, 1) * m(b, 1) + m(a, 2) * m(b, 2);
                if (!(std::abs(dot - (a == b ? 1.0 : 0.0)) < 1e-3)) {
                    capi::invalid("view", "the rotation part is not orthonormal (row " + std::to_string(a) + " . row " +
                                              std::to_string(b) + " = " + capi::number(dot) +
                                              "); expected a rigid view matrix without scale");
                }
            }
        }
        // Camera to world is R^T, -R^T t: the eye at -R^T t, looking down the camera's -Z,
        // which is -(third row of R) in world space.
        kodawari_camera camera{};
        camera.orthographic = orthographic;
        for (int i = 0; i < 3; ++i) {
            const double eye = -(m(0, i) * m(0, 3) + m(1, i) * m(1, 3) + m(2, i) * m(2, 3));
            camera.position[i] = static_cast<float>(eye);
            camera.forward[i] = static_cast<float>(-m(2, i));
        }
        *out = camera;
    });
}

}  // extern "C"
