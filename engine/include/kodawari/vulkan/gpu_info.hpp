#pragma once
/// @file
/// What Vulkan offers on this machine, for `kodawari info` and for messages.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari {

/// One Vulkan physical device and the limits that matter to the compute kernels.
struct GpuDeviceInfo {
    std::uint32_t index = 0;
    std::string name;
    std::string type;         ///< "discrete", "integrated", "virtual", "cpu", "other"
    std::string driver;       ///< driver name and info
    std::string api_version;  ///< "1.3.230"
    bool has_compute_queue = false;
    bool timestamps = false;
    std::uint32_t subgroup_size = 0;
    std::uint32_t max_workgroup_invocations = 0;
    std::uint32_t max_workgroup_size_x = 0;  ///< maxComputeWorkGroupSize[0]
    std::array<std::uint32_t, 3> max_workgroup_count{};
    std::uint64_t max_storage_buffer_range = 0;
    std::uint32_t max_push_constants = 0;
    std::uint32_t max_shared_memory = 0;  ///< maxComputeSharedMemorySize (bytes)
    std::uint64_t device_local_bytes = 0;
    /// Why this device was passed over ("no queue family with compute", "Vulkan 1.0 < 1.1
    /// needed", "does not match \"nvidia\""); "" when it can be chosen.
    std::string rejected;
};

/// All devices, which one would be chosen and why.
struct GpuInventory {
    std::vector<GpuDeviceInfo> devices;
    int chosen = -1;      ///< index into devices, -1 when none fits
    std::string reason;   ///< why that one (or why none, naming each device's reason)
};

/// Lists the Vulkan devices. `request` is a device index or a name substring ("" = the
/// best: discrete > integrated > virtual > cpu). The library reads no environment variable:
/// the `kodawari` command passes KODAWARI_DEVICE here.
/// Fails when there is no Vulkan loader or driver.
[[nodiscard]] KODAWARI_API Result<GpuInventory> list_gpus(const std::string& request);

/// The choice list_gpus() makes, on a list of devices given (a test's, or list_gpus()'s
/// own): `chosen` and `reason` set, and each device a request passes over marked with why
/// (`rejected`). Devices already rejected are never chosen. `request` as for list_gpus();
/// one that matches no usable device leaves `chosen` at -1, its reason naming every device.
KODAWARI_API void choose_gpu(GpuInventory& inventory, const std::string& request);

/// Whether the Khronos validation layer (VK_LAYER_KHRONOS_validation) is installed where the
/// Vulkan loader finds it; false without a loader.
[[nodiscard]] KODAWARI_API bool vulkan_validation_available();

/// Why backend "auto" passes over `device` although it opened: "" for a GPU (discrete,
/// integrated, virtual or other), and for a CPU-type device (Mesa's lavapipe, SwiftShader)
/// a sentence saying so: there the cpu backend runs the same work several times faster
/// than the Vulkan kernels do (docs/performance.md), so "auto" takes it. A device asked
/// for by name or index, and `--backend vulkan`, run on it anyway (Simulation::create and
/// the C API's AUTO ask this only when no device was named).
[[nodiscard]] KODAWARI_API std::string auto_passes_over(const GpuDeviceInfo& device);

}  // namespace kodawari
