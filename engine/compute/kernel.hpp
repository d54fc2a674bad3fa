#pragma once
// A compute kernel: the pipeline of an embedded SPIR-V shader with its binding layout,
// push constants and specialization constants, and its one set of buffer bindings.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "compute/queue.hpp"
#include "core/internal_api.hpp"

namespace kodawari::gpu {
/// SPIR-V of shaders/<name>, compiled at build time (empty when unknown;
/// cmake/embedded_shaders.cpp.in defines it).
[[nodiscard]] std::span<const std::uint32_t> embedded_shader(std::string_view name);
}  // namespace kodawari::gpu

namespace kodawari::compute {

using gpu::embedded_shader;

/// How a kernel reads a binding.
enum class Binding {
    Storage,  ///< std430 storage buffer, read and written
    Uniform,  ///< std140 uniform buffer, read by every invocation (lavapipe loads it once for all lanes)
};

/// A range of a Buffer bound to a binding (the whole buffer by default). `foreign`: a
/// buffer the compute layer does not own (an application's, issue 11), when `buffer` is null.
struct BufferView {
    const Buffer* buffer = nullptr;
    std::uint64_t offset = 0;
    std::uint64_t size = VK_WHOLE_SIZE;
    vk::Buffer foreign{};
};

class KODAWARI_INTERNAL Kernel {
public:
    /// Buffers at bindings 0..n-1 of `bindings`' kinds, `push_bytes` of push constants,
    /// and 32-bit specialization constants with ids 0..m-1.
    [[nodiscard]] static Result<Kernel> create(const Device& device, std::string_view shader, std::span<const Binding> bindings,
                                               std::uint32_t push_bytes, std::span<const std::uint32_t> specialization = {});
    /// The same from SPIR-V the caller holds (a domain's own kernel, compiled outside
    /// the engine); `name` names it in errors. `spirv` is read during the call only.
    [[nodiscard]] static Result<Kernel> create(const Device& device, std::string_view name, std::span<const std::uint32_t> spirv,
                                               std::span<const Binding> bindings, std::uint32_t push_bytes,
                                               std::span<const std::uint32_t> specialization = {});

    Kernel(Kernel&&) noexcept = default;
    Kernel& operator=(Kernel&&) noexcept = default;
    Kernel(const Kernel&) = delete;
    Kernel& operator=(const Kernel&) = delete;
    ~Kernel() = default;

    /// Points binding i at views[i]. Only while no pending submission uses the kernel.
    void bind(std::span<const BufferView> views) const;
    /// Points binding i at the whole of *buffers[i].
    void bind(std::span<const Buffer* const> buffers) const;

    /// Records: binds the kernel and its buffers, pushes constants, dispatches groups_x
    /// workgroups.
    void dispatch(Recording& recording, std::span<const std::byte> push, std::uint32_t groups_x) const;
    /// The same into a Vulkan command buffer the compute layer does not own: the
    /// renderer's frame, which also waits on and signals a window's semaphores.
    void dispatch(const vk::raii::CommandBuffer& cmd, std::span<const std::byte> push, std::uint32_t groups_x) const;

private:
    Kernel() = default;
    const Device* device_ = nullptr;
    vk::raii::DescriptorSetLayout set_layout_{nullptr};
    vk::raii::PipelineLayout layout_{nullptr};
    vk::raii::ShaderModule module_{nullptr};
    vk::raii::Pipeline pipeline_{nullptr};
    vk::raii::DescriptorPool pool_{nullptr};
    vk::raii::DescriptorSet set_{nullptr};
    std::vector<vk::DescriptorType> types_;
};

}  // namespace kodawari::compute
