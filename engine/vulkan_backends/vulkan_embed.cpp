// The embedding entry points (kodawari/vulkan/vulkan_embed.hpp): the application's device
// wrapped as a compute::Device, and the vulkan backends' record_external() behind
// functions that check their arguments first, so that a wrong backend or a null command
// buffer is an error, not a crash.
#include "kodawari/vulkan/vulkan_embed.hpp"

#include <kodawari/shared/birds.h>
#include <kodawari/shared/poses.h>
#include <kodawari/shared/rod_inputs.h>
#include <kodawari/shared/rods.h>

#include <cmath>

#include "vulkan_backends/device_backends.hpp"
#include "gpu/compute_vulkan.hpp"

namespace kodawari {
namespace {

Error not_vulkan(const char* function, const char* argument, std::string_view backend) {
    return make_error(Error::Kind::InvalidInput, std::string(function) + ": " + argument + " is a " + std::string(backend) +
                                                     " backend; recording needs a vulkan one (BackendKind::Vulkan)");
}

// Writes the named entries of each step's input from the application's matrices with
// shaders/rod_inputs.comp, bound once to the rod backend's input buffers (a descriptor set
// must not change while frames in flight use it).
class MatrixInputWriter final : public RodInputWriter {
public:
    MatrixInputWriter(compute::Kernel kernel, compute::Buffer instances, compute::Buffer attachments, gpu::RodInputPush push)
        : kernel_(std::move(kernel)), instances_(std::move(instances)), attachments_(std::move(attachments)), push_(push) {}

    void bind(const MatrixInput& input, const DeviceData& rods) {
        // The application's matrices are its own buffer, not the compute layer's.
        const auto whole = [](const compute::Buffer* b) { return gpu::BufferRange{gpu::vk_buffer(*b)}; };
        const gpu::BufferRange ranges[KW_ROD_INPUTS_BINDING_COUNT] = {
            {input.buffer, input.offset, VkDeviceSize{input.instances} * input.nodes * sizeof(gpu::PoseMatrixGpu)},
            whole(&instances_), whole(&attachments_),
            whole(rods.buffer(rod_buffers::reference).buffer), whole(rods.buffer(rod_buffers::roots).buffer),
            whole(rods.buffer(rod_buffers::colliders).buffer),
            // MatrixInput names no key sources (more.y = 0): they come from the RodFrame.
            whole(rods.buffer(rod_buffers::keys).buffer),
            // Nor centers (more.z = 0; set_matrix_input refuses worlds that have them).
            whole(rods.buffer(rod_buffers::centers).buffer)};
        gpu::bind(kernel_, ranges);
    }

    void record(compute::Recording& recording, const DeviceData&) const override {
        // The frame's own input was just copied into the buffers this kernel overwrites.
        compute::barrier(recording, compute::Stage::Compute | compute::Stage::Transfer, compute::Stage::Compute);
        const std::uint32_t groups = (push_.counts.x + KW_ROD_INPUTS_WORKGROUP_SIZE - 1) / KW_ROD_INPUTS_WORKGROUP_SIZE;
        kernel_.dispatch(recording, std::as_bytes(std::span(&push_, 1)), groups);
    }

private:
    compute::Kernel kernel_;
    compute::Buffer instances_, attachments_;
    gpu::RodInputPush push_;
};

Error bad_input(const std::string& what) { return make_error(Error::Kind::InvalidInput, "set_matrix_input: " + what); }

// Every field of `input` against the backend's world and device, before anything changes.
Result<void> check_matrix_input(const MatrixInput& input, const rods::RodWorld& world, const compute::Device& device) {
    if (input.buffer == VK_NULL_HANDLE) return bad_input("MatrixInput::buffer is null");
    if (input.instances == 0) return bad_input("MatrixInput::instances is 0; expected at least 1");
    if (input.nodes == 0) return bad_input("MatrixInput::nodes is 0; expected at least 1");
    if (input.reference_node >= input.nodes) {
        return bad_input("MatrixInput::reference_node is " + std::to_string(input.reference_node) + "; expected < nodes (" +
                         std::to_string(input.nodes) + ")");
    }
    const VkDeviceSize alignment = gpu::vulkan(device).physical_device().getProperties().limits.minStorageBufferOffsetAlignment;
    if (alignment > 0 && input.offset % alignment != 0) {
        return bad_input("MatrixInput::offset " + std::to_string(input.offset) + " is not a multiple of the device's " +
                         "minStorageBufferOffsetAlignment (" + std::to_string(alignment) + ")");
    }
    if (input.targets.size() != input.instances) {
        return bad_input("MatrixInput::targets has " + std::to_string(input.targets.size()) + " entries; expected one per instance (" +
                         std::to_string(input.instances) + ")");
    }
    for (std::size_t c = 0; c < input.chain_nodes.size(); ++c) {
        if (input.chain_nodes[c] >= input.nodes) {
            return bad_input("MatrixInput::chain_nodes[" + std::to_string(c) + "] is " + std::to_string(input.chain_nodes[c]) +
                             "; expected < nodes (" + std::to_string(input.nodes) + ")");
        }
    }
    for (std::size_t k = 0; k < input.colliders.size(); ++k) {
        const MatrixCollider& m = input.colliders[k];
        const std::string at = "MatrixInput::colliders[" + std::to_string(k) + "]";
        if (m.node >= input.nodes) return bad_input(at + ".node is " + std::to_string(m.node) + "; expected < nodes");
        for (const float v : {m.a[0], m.a[1], m.a[2], m.b[0], m.b[1], m.b[2], m.radius}) {
            if (!std::isfinite(v)) return bad_input(at + " has a value that is not finite");
        }
        if (m.radius < 0.0f) return bad_input(at + ".radius is negative");
    }
    const std::size_t chains = input.chain_nodes.size(), colliders = input.colliders.size();
    for (std::size_t i = 0; i < input.targets.size(); ++i) {
        const MatrixTarget& t = input.targets[i];
        const std::string at = "MatrixInput::targets[" + std::to_string(i) + "]";
        if (t.character >= world.character_count) {
            return bad_input(at + ".character is " + std::to_string(t.character) + "; the world has " +
                             std::to_string(world.character_count) + " characters");
        }
        if (std::uint64_t{t.first_chain} + chains > world.chains.size()) {
            return bad_input(at + ".first_chain " + std::to_string(t.first_chain) + " + " + std::to_string(chains) +
                             " chains passes the world's " + std::to_string(world.chains.size()));
        }
        if (std::uint64_t{t.first_collider} + colliders > world.collider_count) {
            return bad_input(at + ".first_collider " + std::to_string(t.first_collider) + " + " + std::to_string(colliders) +
                             " colliders passes the world's " + std::to_string(world.collider_count));
        }
    }
    return {};
}

}  // namespace

Result<void> set_matrix_input(RodBackend& rods, const MatrixInput& input) {
    auto* device_rods = dynamic_cast<DeviceRodBackend*>(&rods);
    if (device_rods == nullptr) return not_vulkan("set_matrix_input", "rods", rods.name());
    const DeviceData* data = rods.device_data();
    const rods::RodWorld* world = device_rods->world();
    if (data == nullptr || world == nullptr) return bad_input("the backend has no world; load() one first");
    compute::Device& device = device_rods->compute_device();
    KW_TRY(check_matrix_input(input, *world, device));
    if (world->center_count > 0) {
        return bad_input("the world has chains with a center frame (RodFrame::centers), which MatrixInput does not write; "
                         "step it with RodFrame input instead");
    }

    std::vector<gpu::RodInputInstanceGpu> instances;
    for (const MatrixTarget& t : input.targets) instances.push_back({{t.character, t.first_chain, t.first_collider, 0u}, {}});
    std::vector<gpu::RodInputAttachmentGpu> attachments;
    for (const std::uint32_t node : input.chain_nodes) attachments.push_back({{node, 0u, 0u, 0u}, {}, {}});
    for (const MatrixCollider& m : input.colliders) {
        attachments.push_back({{m.node, 0u, 0u, 0u}, {m.a[0], m.a[1], m.a[2], m.radius}, {m.b[0], m.b[1], m.b[2], 0.0f}});
    }
    const std::uint64_t sizes[] = {instances.size() * sizeof(gpu::RodInputInstanceGpu),
                                   attachments.size() * sizeof(gpu::RodInputAttachmentGpu)};
    auto buffers = compute::create_storage_buffers(device, sizes, "the matrix input's tables");
    if (!buffers) return buffers.error();
    KW_TRY(compute::upload(device, buffers.value()[0], std::as_bytes(std::span(instances))));
    KW_TRY(compute::upload(device, buffers.value()[1], std::as_bytes(std::span(attachments))));
    const std::vector<compute::Binding> types(KW_ROD_INPUTS_BINDING_COUNT, compute::Binding::Storage);
    auto kernel = compute::Kernel::create(device, "rod_inputs", types, sizeof(gpu::RodInputPush));
    if (!kernel) return kernel.error();
    const gpu::RodInputPush push{{input.instances, input.nodes, input.reference_node, static_cast<std::uint32_t>(input.chain_nodes.size())},
                                 {static_cast<std::uint32_t>(input.colliders.size()), 0u, 0u, 0u}};
    auto writer = std::make_shared<MatrixInputWriter>(std::move(kernel).value(), std::move(buffers.value()[0]),
                                                      std::move(buffers.value()[1]), push);
    writer->bind(input, *data);
    device_rods->set_input_writer(std::move(writer));
    return {};
}

Result<void> clear_matrix_input(RodBackend& rods) {
    auto* device_rods = dynamic_cast<DeviceRodBackend*>(&rods);
    if (device_rods == nullptr) return not_vulkan("clear_matrix_input", "rods", rods.name());
    device_rods->set_input_writer(nullptr);
    return {};
}

VulkanRequirements vulkan_requirements() { return {}; }

Result<std::shared_ptr<compute::Device>> adopt_vulkan_device(const VulkanDeviceHandles& handles) {
    auto adopted = gpu::VulkanContext::adopt({.instance = handles.instance,
                                              .physical_device = handles.physical_device,
                                              .device = handles.device,
                                              .queue_family = handles.queue_family,
                                              .queue_index = handles.queue_index,
                                              .get_instance_proc_addr = handles.get_instance_proc_addr,
                                              .allocator = handles.allocator,
                                              .api_version = handles.api_version,
                                              .frames_in_flight = handles.frames_in_flight});
    if (!adopted) return adopted.error();
    return std::shared_ptr<compute::Device>(std::move(adopted).value());
}

Result<VulkanBufferRange> vulkan_buffer(const DeviceData& data, std::string_view name) {
    const DeviceSpan span = data.buffer(name);
    if (span.buffer == nullptr) {
        return make_error(Error::Kind::InvalidInput, "vulkan_buffer: the backend keeps no buffer named \"" + std::string(name) +
                                                         "\" now (another family's, or not loaded yet)");
    }
    return vulkan_range(span);
}

Result<compute::Recording> borrow_command_buffer(compute::Device& device, VkCommandBuffer cmd) {
    if (cmd == VK_NULL_HANDLE) return make_error(Error::Kind::InvalidInput, "borrow_command_buffer: cmd is null");
    return gpu::borrow(device, cmd, nullptr);
}

VulkanBufferRange vulkan_range(const compute::Buffer& buffer, std::uint32_t count, std::uint32_t stride, VkDeviceSize offset) {
    VulkanBufferRange out;
    out.buffer = static_cast<VkBuffer>(gpu::vk_buffer(buffer));
    out.offset = offset;
    out.count = count;
    out.stride = stride;
    out.range = VkDeviceSize{count} * stride;
    return out;
}

namespace {

// The vulkan side of `backend`, which every record call needs, with `recording` checked
// to be on its device (the module's buffers are not on another one).
template <typename DeviceBackend, typename Backend>
Result<DeviceBackend*> recorder(Backend& backend, const compute::Recording& recording, const char* function, const char* argument) {
    auto* device = dynamic_cast<DeviceBackend*>(&backend);
    if (device == nullptr) return not_vulkan(function, argument, backend.name());
    if (&recording.device() != &device->compute_device()) {
        return make_error(Error::Kind::InvalidInput, std::string(function) + ": recording is on another device (" +
                                                         recording.device().info().name + ") than the backend's (" +
                                                         device->compute_device().info().name + ")");
    }
    return device;
}

// The command-buffer forms: the application's command buffer borrowed on the backend's
// device, for the Recording forms below.
template <typename DeviceBackend, typename Backend>
Result<compute::Recording> borrow_for(Backend& backend, VkCommandBuffer cmd, const char* function, const char* argument) {
    if (cmd == VK_NULL_HANDLE) return make_error(Error::Kind::InvalidInput, std::string(function) + ": cmd is null");
    auto* device = dynamic_cast<DeviceBackend*>(&backend);
    if (device == nullptr) return not_vulkan(function, argument, backend.name());
    return gpu::borrow(device->compute_device(), cmd, nullptr);
}

}  // namespace

Result<void> record_step(RodBackend& rods, compute::Recording& recording, const rods::RodFrame& frame) {
    auto device = recorder<DeviceRodBackend>(rods, recording, "record_step", "rods");
    if (!device) return device.error();
    return device.value()->record_external(recording, frame);
}

Result<void> record_simulate(BirdBackend& birds, compute::Recording& recording, std::uint32_t frames) {
    auto device = recorder<DeviceBirdBackend>(birds, recording, "record_simulate", "birds");
    if (!device) return device.error();
    return device.value()->record_external(recording, frames, nullptr);
}

Result<void> record_evaluate(PoseBackend& poses, compute::Recording& recording, float time) {
    auto device = recorder<DevicePoseBackend>(poses, recording, "record_evaluate", "poses");
    if (!device) return device.error();
    return device.value()->record_external(recording, time);
}

Result<void> record_step(RodBackend& rods, VkCommandBuffer cmd, const rods::RodFrame& frame) {
    auto recording = borrow_for<DeviceRodBackend>(rods, cmd, "record_step", "rods");
    if (!recording) return recording.error();
    return record_step(rods, recording.value(), frame);
}

Result<void> record_simulate(BirdBackend& birds, VkCommandBuffer cmd, std::uint32_t frames) {
    auto recording = borrow_for<DeviceBirdBackend>(birds, cmd, "record_simulate", "birds");
    if (!recording) return recording.error();
    return record_simulate(birds, recording.value(), frames);
}

Result<void> record_evaluate(PoseBackend& poses, VkCommandBuffer cmd, float time) {
    auto recording = borrow_for<DevicePoseBackend>(poses, cmd, "record_evaluate", "poses");
    if (!recording) return recording.error();
    return record_evaluate(poses, recording.value(), time);
}

}  // namespace kodawari
