#pragma once
/// @file
/// Kodawari as a compute module on the application's own Vulkan device, recording into
/// the application's own command buffers (kodawari::vulkan; docs/embedding.md).
///
///     auto device = kodawari::adopt_vulkan_device({.instance = ..., .physical_device = ...,
///                                                  .device = ..., .queue_family = family,
///                                                  .get_instance_proc_addr = vkGetInstanceProcAddr,
///                                                  .api_version = VK_API_VERSION_1_3});
///     BackendOptions options{.context = device.value()};
///     auto rods = make_rod_backend(BackendKind::Vulkan, options);   // backend_factory.hpp
///     rods.value()->load(world, first_frame);          // submits once to the queue, waits
///     // each frame, while recording the application's command buffer:
///     record_step(*rods.value(), cmd, frame);          // no submit, no wait
///     auto joints = vulkan_buffer(*rods.value()->device_data(), rod_buffers::motion);
///     // bind joints.value().buffer at joints.value().offset in the application's shaders
///
/// What the module needs from the device: vulkan_requirements(). What it records and how
/// the application's work is ordered with it: "Synchronization" below.

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include <vulkan/vulkan_core.h>

#include "kodawari/core/api.hpp"
#include "kodawari/backends/backend.hpp"
#include "kodawari/vulkan/compute.hpp"
#include "kodawari/backends/device_data.hpp"
#include "kodawari/backends/pose_backend.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/backends/rod_backend.hpp"

namespace kodawari {

/// The application's Vulkan objects the module runs on. It creates its own objects on
/// `device` (buffers, pipelines, a command pool for load() and read-back) with
/// `allocator`, and destroys neither the instance nor the device.
struct VulkanDeviceHandles {
    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physical_device = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    /// The family of the command buffers the application passes to record_*(); it must do
    /// compute. Where it also does graphics, the module's barriers cover the application's
    /// draws too.
    std::uint32_t queue_family = 0;
    /// The queue of that family that load() and read-back submit to (and wait on). The
    /// device must have been created with it. The application must not use this queue from
    /// another thread during those calls (Vulkan's external synchronization of queues).
    std::uint32_t queue_index = 0;
    /// The application's loader entry point (vkGetInstanceProcAddr): every call goes
    /// through it, so that the module works with a statically linked loader or volk.
    PFN_vkGetInstanceProcAddr get_instance_proc_addr = nullptr;
    /// Used for every object the module creates on the device; null: the driver's.
    const VkAllocationCallbacks* allocator = nullptr;
    /// VkApplicationInfo::apiVersion the instance was created with (1.1 or later).
    std::uint32_t api_version = 0;
    /// Frames the application records ahead of the GPU (1 to 16): the depth of each
    /// backend's ring of per-frame input uploads. When the application records frame k,
    /// the GPU must have finished frame k - frames_in_flight (the usual fence per frame).
    std::uint32_t frames_in_flight = 2;
};

/// What the module needs from a device: Vulkan 1.1 (its SPIR-V's target), a queue family
/// with compute, and no feature or extension beyond the core (the kernels use only the
/// Shader capability). Timestamps are used where present.
struct VulkanRequirements {
    std::uint32_t api_version = VK_API_VERSION_1_1;
    VkQueueFlags queue_flags = VK_QUEUE_COMPUTE_BIT;
    std::uint32_t device_extension_count = 0;  ///< none
};
[[nodiscard]] KODAWARI_API VulkanRequirements vulkan_requirements();

/// Wraps the application's device for BackendOptions::context: every vulkan backend made
/// with it (make_rod_backend, make_bird_backend, make_pose_backend) runs there. Errors
/// (InvalidInput naming the VulkanDeviceHandles field, or Unsupported naming what the
/// device lacks) are returned before any call through a handle that could be bad. The
/// returned object must be released (with every backend made on it) before the
/// application destroys its device, and once the GPU finished the work recorded with it.
[[nodiscard]] KODAWARI_API Result<std::shared_ptr<compute::Device>> adopt_vulkan_device(const VulkanDeviceHandles& handles);


/// A range of a buffer on the Simulation's Vulkan device, to bind in the application's
/// shaders (vulkan_buffer(), Simulation::buffer()). The element layout is the std430
/// struct its owner names with the buffer, defined in <kodawari/shared/*.h> for GLSL and
/// C++ alike.
struct VulkanBufferRange {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceSize offset = 0;  ///< bytes from the buffer's start to the first element
    VkDeviceSize range = 0;   ///< bytes: count x stride
    std::uint32_t count = 0;  ///< elements
    std::uint32_t stride = 0; ///< bytes per element (the struct's size)
};

/// A compute::Recording (kodawari/vulkan/compute.hpp) into `cmd`, a command buffer of the
/// application's in the recording state on `device` (adopt_vulkan_device()'s), of
/// VulkanDeviceHandles::queue_family: what Simulation::record() and a domain's
/// Domain::record() record into. Nothing is submitted, waited for or freed through it; it
/// must not outlive `cmd` or the device. InvalidInput when `cmd` is null.
[[nodiscard]] KODAWARI_API Result<compute::Recording> borrow_command_buffer(compute::Device& device, VkCommandBuffer cmd);

/// `count` elements of `stride` bytes of a compute::Buffer from `offset`, as a range to
/// bind in the application's shaders (what a domain's Domain::buffer() hands out).
[[nodiscard]] KODAWARI_API VulkanBufferRange vulkan_range(const compute::Buffer& buffer, std::uint32_t count,
                                                         std::uint32_t stride, VkDeviceSize offset = 0);

/// Where a backend's named buffer is now (after load(), or after the first record for
/// birds and poses); InvalidInput when the backend keeps no such buffer. Ranges stay
/// valid until the backend's next load() (bird poses: until the next record_simulate,
/// which may use another slot of its ring).
[[nodiscard]] KODAWARI_API Result<VulkanBufferRange> vulkan_buffer(const DeviceData& data, std::string_view name);

/// Records one frame of `rods` (a vulkan rod backend, loaded) into `cmd`, a command buffer
/// of VulkanDeviceHandles::queue_family in the recording state: the frame's input copied
/// from the backend's staging ring, then the step's dispatch (SPEC A.4), between the
/// barriers below. Nothing is submitted or waited for; the new state is in the backend's
/// buffers once the application's submission completed. `frame` is checked
/// (rods::check_frame) before anything is recorded: on error, `cmd` and the backend are
/// as they were.
[[nodiscard]] KODAWARI_API Result<void> record_step(RodBackend& rods, VkCommandBuffer cmd, const rods::RodFrame& frame);

/// Records the next `frames` frames of `birds` (a vulkan bird backend, loaded) into `cmd`;
/// bird_buffers::poses then holds the last of them.
[[nodiscard]] KODAWARI_API Result<void> record_simulate(BirdBackend& birds, VkCommandBuffer cmd, std::uint32_t frames);

/// Records the evaluation of every instance of `poses` (a vulkan pose backend, loaded) at
/// scene time `time` into `cmd`; pose_buffers::world then holds the world matrices.
[[nodiscard]] KODAWARI_API Result<void> record_evaluate(PoseBackend& poses, VkCommandBuffer cmd, float time);

/// The same three into a compute::Recording: one an application borrowed
/// (borrow_command_buffer(), what the VkCommandBuffer calls above make), or one of the
/// module's own queue (compute::Queue::begin() on the backends' device), so that a
/// program without Vulkan code of its own submits several backends' frames at once:
///
///     compute::Queue queue(*device);
///     auto recording = queue.begin();
///     record_step(*rods, recording.value(), frame);   // the chains' frame
///     record_simulate(*birds, recording.value(), 1);  // and the flock's, same submission
///     queue.submit(std::move(recording).value()).value().wait();
///
/// InvalidInput when the recording is on another device than the backend's, naming
/// `recording`; the synchronization is the VkCommandBuffer calls'. A recording of the
/// module's queue may hold several frames of a backend as long as they fit its ring of
/// frames in flight (VulkanDeviceHandles::frames_in_flight).
[[nodiscard]] KODAWARI_API Result<void> record_step(RodBackend& rods, compute::Recording& recording, const rods::RodFrame& frame);
[[nodiscard]] KODAWARI_API Result<void> record_simulate(BirdBackend& birds, compute::Recording& recording, std::uint32_t frames);
[[nodiscard]] KODAWARI_API Result<void> record_evaluate(PoseBackend& poses, compute::Recording& recording, float time);

/// A collider of a matrix-driven character: a capsule (a sphere when a == b) in a node's frame.
struct MatrixCollider {
    std::uint32_t node = 0;           ///< the node whose matrix carries it
    std::array<float, 3> a{};         ///< end a in the node's frame (m)
    std::array<float, 3> b{};         ///< end b in the node's frame (m)
    float radius = 0.0f;              ///< m, >= 0
};

/// Where one instance's input goes in the rod world.
struct MatrixTarget {
    std::uint32_t character = 0;      ///< its reference joint: RodFrame::reference[character]
    std::uint32_t first_chain = 0;    ///< its chains: RodFrame::roots[first_chain ...]
    std::uint32_t first_collider = 0; ///< its colliders: RodFrame::colliders[first_collider ...]
};

/// The kinematic input of characters taken, on the device, from world matrices the
/// application already has in a buffer of its own: `instances` x `nodes` matrices
/// (4 x 4 floats, column-major, 64 bytes each, instance-major: PoseMatrixGpu of
/// <kodawari/shared/poses.h>), all instances sharing one skeleton layout. Each step then
/// writes, per instance, the reference joint from `reference_node`, the root of its chains
/// from `chain_nodes` and its colliders, each node's transform being the matrix's
/// translation and the rotation of its normalized columns (a mirror made proper), as for
/// the rigged characters of a scene (shaders/rod_inputs.comp).
struct MatrixInput {
    VkBuffer buffer = VK_NULL_HANDLE;  ///< the application's; a storage buffer
    VkDeviceSize offset = 0;           ///< a multiple of minStorageBufferOffsetAlignment
    std::uint32_t instances = 0;       ///< N, >= 1
    std::uint32_t nodes = 0;           ///< M matrices per instance, >= 1
    std::uint32_t reference_node = 0;  ///< < nodes
    std::vector<std::uint32_t> chain_nodes;  ///< per chain of an instance: its root's node
    std::vector<MatrixCollider> colliders;   ///< per collider of an instance
    std::vector<MatrixTarget> targets;       ///< one per instance
};

/// From now on every step of `rods` (a vulkan rod backend, loaded) takes the entries
/// `input` names from the application's matrices, read on the device when the step runs:
/// the application writes them (by its kernels, copies or the host, ordered before the
/// step as any input of its command buffer) and passes the other entries in the RodFrame
/// as usual (those it names are overwritten). The buffer must outlive the backend's
/// steps. Call again after each load(). Checked in full first (InvalidInput naming the
/// field and index; the backend unchanged on error).
[[nodiscard]] KODAWARI_API Result<void> set_matrix_input(RodBackend& rods, const MatrixInput& input);
/// Back to the RodFrame's entries alone.
[[nodiscard]] KODAWARI_API Result<void> clear_matrix_input(RodBackend& rods);

// Synchronization (docs/embedding.md). Each record_*() call records, in `cmd`:
//   1. a memory barrier from the application's earlier reads of the module's buffers —
//      stages COMPUTE_SHADER | TRANSFER, plus VERTEX_INPUT | VERTEX_SHADER |
//      FRAGMENT_SHADER on a family that draws — to the module's TRANSFER (input copies)
//      and COMPUTE_SHADER (its kernels): the previous frame's draws finish reading before
//      this frame overwrites;
//   2. its copies and dispatches (with barriers between them);
//   3. a memory barrier from its COMPUTE_SHADER writes (SHADER_WRITE) to the same
//      consumer stages with SHADER_READ | TRANSFER_READ | VERTEX_ATTRIBUTE_READ.
// So a draw (or a kernel, or a copy) recorded after record_*() in the same command buffer,
// or in a later submission to the same queue, reads the new frame without a barrier of its
// own. Work on another queue needs the application's semaphore. Reads in other stages
// (e.g. indirect draws, task or mesh shaders) need the application's own barrier.
}  // namespace kodawari
