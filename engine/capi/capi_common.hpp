#pragma once
// What every part of the C API shares: the boundary that turns C++ failures into status
// codes and messages (no exception crosses into C), the argument checks that name the
// argument and index that is wrong, and the conversions from C arrays to glm types.
//
// Checks throw a Rejection, which guard() catches: a body first checks everything, then
// changes state, so a rejected call changes nothing (kodawari.h's promise).

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <string>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/backends/backend.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/kodawari.h"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/chain_snapshot.hpp"
#include "kodawari/rods/wind.hpp"
#include "kodawari/vulkan/vulkan_embed.hpp"

/// kodawari_vulkan_device_adopt's handle: the application's device, wrapped
/// (kodawari::adopt_vulkan_device); shared with the worlds made on it.
struct kodawari_vulkan_device {
    std::shared_ptr<kodawari::compute::Device> context;
};

namespace kodawari::capi {

/// A call refused with a status and a message; thrown by the checks, caught by guard().
struct Rejection {
    kodawari_status status;
    std::string message;
};

[[noreturn]] void reject(kodawari_status status, std::string message);
/// Rejects with KODAWARI_INVALID_ARGUMENT: "`what`: `problem`".
[[noreturn]] void invalid(const std::string& what, const std::string& problem);
/// Turns an engine Error into a Rejection with the status its kind and VkResult say.
[[noreturn]] void fail(const Error& error);
/// KW_TRY for the C API: rejects with the error of a failed Result.
template <typename T>
void check(const Result<T>& result) {
    if (!result.ok()) fail(result.error());
}

/// Shortest text that reads back as the same float ("2e-07", "0.1", "nan").
std::string number(double value);

/// The boundary of every entry point: runs `body` (which returns nothing and reports
/// problems by throwing) and turns whatever it throws into a status, prefixing the message
/// with `function`. The message goes to this thread's last error and, when `handle_message`
/// is given, to the handle's; both are "" after a success.
template <typename Body>
kodawari_status guard(const char* function, std::string* handle_message, Body&& body) noexcept;

/// This thread's last error, for kodawari_last_error().
const char* last_error_text() noexcept;

/// Sets this thread's last error (and the handle's) for a call's outcome.
void record(kodawari_status status, const char* function, const std::string& message, std::string* handle_message) noexcept;

template <typename Body>
kodawari_status guard(const char* function, std::string* handle_message, Body&& body) noexcept {
    kodawari_status status = KODAWARI_INTERNAL;
    std::string message;
    try {
        body();
        status = KODAWARI_OK;
    } catch (const Rejection& r) {
        status = r.status;
        message = r.message;
    } catch (const std::bad_alloc&) {
        status = KODAWARI_OUT_OF_MEMORY;
        message = "out of host memory";
    } catch (const std::exception& e) {
        // No engine path throws on purpose (errors are Results): this is a bug.
        message = std::string("unexpected exception: ") + e.what();
    } catch (...) {
        message = "unexpected exception of an unknown type";
    }
    record(status, function, message, handle_message);
    return status;
}

// ---- Argument checks: each names `what` (an argument path such as "desc->chains[3].mass").

/// "`base`[`index`]".
std::string at(const std::string& base, std::size_t index);

/// A pointer that must not be NULL.
void require_pointer(const void* pointer, const std::string& what);
/// An array of `count` elements: NULL only when count is 0.
void require_array(const void* pointer, std::size_t count, const std::string& what, const std::string& count_name);
/// A uint32_t boolean: 0 or 1.
void require_flag(std::uint32_t value, const std::string& what);
/// A finite number in [low, high] (open at either end when asked).
void require_range(float value, double low, double high, const std::string& what, bool low_open = false,
                   bool high_open = false);
/// Finite coordinates with |each| <= limit.
void require_point(const float* xyz, double limit, const std::string& what);
/// A checked wind field (`what` names the argument): every kodawari_wind range.
rods::WindField read_wind(const kodawari_wind& wind, const std::string& what);
/// The C form of a wind field.
kodawari_wind to_c(const rods::WindField& wind);
/// A unit quaternion (x, y, z, w), length within 1e-3 of 1.
void require_unit_quat(const float* xyzw, const std::string& what);
/// A finite vector of length >= 1e-6 (and |each| <= 1e6, so that its square is finite).
void require_direction(const float* xyz, const std::string& what);
/// A rigid transform: position within 1e6 m, a unit rotation.
void require_transform(const kodawari_transform& t, const std::string& what);
/// A capsule: ends within `limit` m, radius in [0, limit].
void require_capsule(const kodawari_capsule& c, double limit, const std::string& what);
/// A camera: a perspective/orthographic flag, position within 1e6 m, non-zero forward.
void require_camera(const kodawari_camera& camera, const std::string& what);

/// The value a C caller put in an enum field, read as its 32 bits: C lets any int into an
/// enum, but in C++ loading a value outside the enumerators' range is undefined (UBSan's
/// -fsanitize=enum), so the checks read the bits, never the enum.
template <typename Enum>
std::int64_t enum_value(const Enum& value) {
    static_assert(sizeof(Enum) == sizeof(std::int32_t), "kodawari.h's enums are 32-bit (their *_MAX_ENUM)");
    std::int32_t bits = 0;
    std::memcpy(&bits, &value, sizeof bits);
    return bits;
}

// ---- Conversions (after the checks).

inline glm::vec3 vec3(const float* p) { return {p[0], p[1], p[2]}; }
inline glm::quat quat(const float* p) { return {p[3], p[0], p[1], p[2]}; }  // glm: (w, x, y, z)

// ---- Backends.

/// The backend `options` make: AUTO on the application's device is VULKAN.
kodawari_backend effective_backend(const kodawari_backend_options& options);
/// Where a device buffer is, in C (`what` names the argument in errors).
void fill_range(const DeviceData* data, kodawari_device_buffer which, kodawari_buffer_range* out, bool chains);
/// The engine's name of a C buffer name; InvalidInput naming `which` when out of range.
std::string_view device_buffer(kodawari_device_buffer which);
/// A VulkanBufferRange as the C API writes it.
kodawari_buffer_range buffer_range(const VulkanBufferRange& range);
/// The engine's kind of an explicit kodawari_backend (not AUTO).
BackendKind backend_kind(kodawari_backend backend);
kodawari_backend backend_enum(BackendKind kind);
/// Checks `options` (the enum, the flags, the thread count) and names problems under `what`.
void require_backend_options(const kodawari_backend_options& options, const std::string& what);
BackendOptions backend_options(const kodawari_backend_options& options);
/// Opens the backend `options` ask for (for the chain and bird worlds) and loads the
/// world into it with `load(backend)`; `kind` says which it is. AUTO takes vulkan, made by
/// `make(BackendKind::Vulkan, options)`, when a GPU (or a named device) opens and the world
/// fits it, else cpu with `reason` saying why, as Simulation::create does: a CPU-type
/// device nobody named (lavapipe: the cpu backend is faster) or no device
/// (open_auto_device()), or a world larger than the device can bind (Unsupported, which
/// the CPU backends do not know). A `device` that names nothing, and any other error,
/// throw (check()): never a reason to run elsewhere. A device the caller lent is always
/// used (effective_backend).
template <typename Backend, typename Make, typename Load>
std::unique_ptr<Backend> open_and_load(const kodawari_backend_options& c_options, BackendKind& kind, std::string& reason,
                                       Make make, Load load) {
    BackendOptions options = backend_options(c_options);
    if (effective_backend(c_options) == KODAWARI_BACKEND_AUTO) {
        kind = BackendKind::Vulkan;
        auto device = open_auto_device(options, reason);
        check(device);
        if (device.value()) {
            options.context = std::move(device).value();
            auto vulkan = make(BackendKind::Vulkan, options);
            if (vulkan.ok()) {
                std::unique_ptr<Backend> backend = std::move(vulkan).value();
                const auto loaded = load(*backend);
                if (loaded.ok()) return backend;
                if (loaded.error().kind != Error::Kind::Unsupported) check(loaded);
                reason = loaded.error().message;
            } else {
                if (!options.device.empty()) check(vulkan);
                reason = vulkan.error().message;
            }
        }
        kind = BackendKind::Cpu;
    } else {
        kind = backend_kind(effective_backend(c_options));
    }
    auto made = make(kind, options);
    check(made);
    std::unique_ptr<Backend> backend = std::move(made).value();
    check(load(*backend));
    return backend;
}

/// Copies `text` into `out[size]`, cut to fit and always terminated.
void copy_text(const std::string& text, char* out, std::size_t size);

/// A capacity check of one output array: `what` (a field of the output struct) holds
/// `capacity` floats and needs `needed` (`count_text` says why, "12 joints x 3").
void require_capacity(const void* pointer, std::size_t capacity, std::size_t needed, const std::string& what,
                      const std::string& count_text);

/// The capacity checks of a kodawari_chain_output for `joints` joints and `chains` chains
/// (each array it asks for), naming the field.
void require_chain_output(const kodawari_chain_output& out, std::size_t joints, std::size_t chains);
/// Writes `s` into the arrays `out` asks for (require_chain_output() first): positions,
/// orientations (x y z w), rest positions, view directions and weights.
void write_chain_output(const ChainSnapshot& s, const kodawari_chain_output& out);

}  // namespace kodawari::capi
