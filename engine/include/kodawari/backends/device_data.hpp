#pragma once
/// @file
/// What a backend keeps on its device, for other GPU work on that device (the renderer
/// draws from it, the crowd animator writes the rod input from the pose matrices) without
/// a copy back to the host (issue 5). One typed interface for every backend family,
/// naming no graphics-API type: buffers are the compute layer's (kodawari/vulkan/compute.hpp).

#include <cstdint>
#include <string_view>

#include "kodawari/core/api.hpp"

namespace kodawari {

namespace compute {
class Device;
}
namespace compute {
class Buffer;
}

/// Where a named buffer's current data is. Names belong to each backend family and are
/// listed in its header (bird_buffers in backend.hpp, rod_buffers in rod_backend.hpp,
/// pose_buffers in pose_backend.hpp), with the std430 element struct of each in
/// <kodawari/shared/*.h>: there is no list of every family's buffers, so a new family
/// names its own.
struct DeviceSpan {
    const compute::Buffer* buffer = nullptr;  ///< null: the backend keeps no such buffer (now)
    std::uint64_t first = 0;                  ///< the first element of the current data (bird poses: bird 0 of the last frame)
    std::uint32_t items = 0;                  ///< birds, chains, joints, instances
    std::uint32_t per_item = 1;               ///< elements per item (pose world matrices: nodes)
    std::uint32_t element_bytes = 0;          ///< bytes per element: the element struct's size
};

/// A backend's data on its device (BirdBackend, RodBackend, PoseBackend::device_data()).
class KODAWARI_API DeviceData {
public:
    virtual ~DeviceData() = default;
    /// The device the buffers live on: compare with a renderer's before drawing from them.
    [[nodiscard]] virtual const compute::Device& context() const = 0;
    /// A named buffer (its family's names); {} when this backend has none (another
    /// family's name, an unknown one, or not loaded).
    [[nodiscard]] virtual DeviceSpan buffer(std::string_view name) const = 0;

protected:
    DeviceData() = default;
    DeviceData(const DeviceData&) = default;
    DeviceData& operator=(const DeviceData&) = default;
};

}  // namespace kodawari
