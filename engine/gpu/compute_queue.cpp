// compute::Queue, Recording and Submission on Vulkan (kodawari/vulkan/compute.hpp): command slots
// from the context, fences, pipeline barriers and copies.
#include "gpu/compute_vulkan.hpp"

#include <cassert>
#include <algorithm>
#include <cstring>

namespace kodawari::compute {
namespace {

struct Access {
    vk::PipelineStageFlags stages;
    vk::AccessFlags access;
};

Access source(Stage s) {
    Access a;
    if (has(s, Stage::Compute)) a = {a.stages | vk::PipelineStageFlagBits::eComputeShader, a.access | vk::AccessFlagBits::eShaderWrite};
    if (has(s, Stage::Transfer)) a = {a.stages | vk::PipelineStageFlagBits::eTransfer, a.access | vk::AccessFlagBits::eTransferWrite};
    if (has(s, Stage::Host)) a = {a.stages | vk::PipelineStageFlagBits::eHost, a.access | vk::AccessFlagBits::eHostWrite};
    // Reads only: later writes wait for them (an execution dependency, no access).
    if (has(s, Stage::Vertex)) a.stages |= vk::PipelineStageFlagBits::eVertexShader;
    if (has(s, Stage::Draw)) {
        a.stages |= vk::PipelineStageFlagBits::eVertexInput | vk::PipelineStageFlagBits::eVertexShader |
                    vk::PipelineStageFlagBits::eFragmentShader;
    }
    return a;
}

Access destination(Stage s) {
    Access a;
    // Uniform buffers (Binding::Uniform) are read through UNIFORM_READ, which SHADER_READ
    // does not cover (Vulkan's access types): a copy that wrote one (the rods' templates when
    // dt changes) must be made visible to it by name.
    if (has(s, Stage::Compute)) {
        a = {a.stages | vk::PipelineStageFlagBits::eComputeShader,
             a.access | vk::AccessFlagBits::eUniformRead | vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite};
    }
    if (has(s, Stage::Transfer)) {
        a = {a.stages | vk::PipelineStageFlagBits::eTransfer, a.access | vk::AccessFlagBits::eTransferRead | vk::AccessFlagBits::eTransferWrite};
    }
    if (has(s, Stage::Host)) a = {a.stages | vk::PipelineStageFlagBits::eHost, a.access | vk::AccessFlagBits::eHostRead};
    if (has(s, Stage::Vertex)) {
        a = {a.stages | vk::PipelineStageFlagBits::eVertexShader,
             a.access | vk::AccessFlagBits::eUniformRead | vk::AccessFlagBits::eShaderRead};
    }
    if (has(s, Stage::Draw)) {
        a = {a.stages | vk::PipelineStageFlagBits::eVertexInput | vk::PipelineStageFlagBits::eVertexShader |
                 vk::PipelineStageFlagBits::eFragmentShader,
             a.access | vk::AccessFlagBits::eVertexAttributeRead | vk::AccessFlagBits::eUniformRead | vk::AccessFlagBits::eShaderRead};
    }
    return a;
}

}  // namespace

Recording::Recording(Device& device, std::unique_ptr<Native> native) : device_(&device), native_(std::move(native)) {}

Recording::Recording(Recording&& other) noexcept
    : device_(std::exchange(other.device_, nullptr)),
      native_(std::move(other.native_)),
      kept_(std::move(other.kept_)),
      staging_(std::exchange(other.staging_, nullptr)),
      borrowed_(std::exchange(other.borrowed_, false)) {}

Recording& Recording::operator=(Recording&& other) noexcept {
    if (this != &other) {
        release();
        device_ = std::exchange(other.device_, nullptr);
        native_ = std::move(other.native_);
        kept_ = std::move(other.kept_);
        staging_ = std::exchange(other.staging_, nullptr);
        borrowed_ = std::exchange(other.borrowed_, false);
    }
    return *this;
}

Recording::~Recording() { release(); }

Recording Recording::borrow(Device& device, std::unique_ptr<Native> native, StagingRing* staging) {
    Recording out(device, std::move(native));
    out.staging_ = staging;
    out.borrowed_ = true;
    return out;
}

Recording Recording::share(StagingRing* staging) const {
    return gpu::borrow(*device_, static_cast<VkCommandBuffer>(*native_->slot.cmd), staging);
}

void Recording::release() {
    if (native_ == nullptr) return;  // moved from
    if (borrowed_) {
        (void)native_->slot.cmd.release();  // not ours to free
        native_.reset();
        staging_ = nullptr;
        borrowed_ = false;
        device_ = nullptr;
        return;
    }
    // Never submitted: nothing runs, the command buffer is reset at its next begin().
    if (device_ != nullptr) gpu::vulkan(*device_).release_slot(std::move(native_->slot));
    native_.reset();
    device_ = nullptr;
    kept_.clear();
}

void Recording::keep(Buffer buffer) {
    assert(!borrowed_ && "a borrowed command buffer has no submission to keep a buffer for");
    kept_.push_back(std::move(buffer));
}

void Recording::timestamp(Timestamp which) {
    if (borrowed_) return;
    gpu::vulkan(*device_).write_timestamp(native_->slot.cmd, which == Timestamp::Begin ? 0 : 1,
                                          which == Timestamp::Begin ? vk::PipelineStageFlagBits::eTopOfPipe
                                                                    : vk::PipelineStageFlagBits::eBottomOfPipe);
}

Submission::Submission(Recording recording)
    : device_(std::exchange(recording.device_, nullptr)),
      native_(std::move(recording.native_)),
      kept_(std::move(recording.kept_)) {}

Submission::Submission(Submission&& other) noexcept
    : device_(std::exchange(other.device_, nullptr)), native_(std::move(other.native_)), kept_(std::move(other.kept_)) {}

Submission& Submission::operator=(Submission&& other) noexcept {
    if (this != &other) {
        (void)wait();
        device_ = std::exchange(other.device_, nullptr);
        native_ = std::move(other.native_);
        kept_ = std::move(other.kept_);
    }
    return *this;
}

Submission::~Submission() { (void)wait(); }

Result<void> Submission::wait(double* gpu_ms) {
    if (gpu_ms != nullptr) *gpu_ms = -1.0;
    if (device_ == nullptr) return {};
    gpu::VulkanContext& device = gpu::vulkan(*device_);
    gpu::CommandSlot& slot = native_->slot;
    auto waited = guard("Vulkan submission", [&]() -> Result<void> {
        constexpr std::uint64_t kTimeoutNs = 600ull * 1000 * 1000 * 1000;
        if (device.device().waitForFences(*slot.fence, VK_TRUE, kTimeoutNs) != vk::Result::eSuccess) {
            Error error = make_error(Error::Kind::Vulkan, "the GPU did not finish within 600 s");
            error.vk_result = static_cast<int>(vk::Result::eTimeout);
            return error;
        }
        if (gpu_ms != nullptr) *gpu_ms = device.timestamp_ms();
        return {};
    });
    if (!waited) return waited;  // still pending: the destructor must not free what runs
    device_ = nullptr;
    device.release_slot(std::move(slot));
    native_.reset();
    kept_.clear();
    return {};
}

Result<Recording> Queue::begin() const {
    gpu::VulkanContext& device = gpu::vulkan(*device_);
    auto slot = device.acquire_slot();
    if (!slot) return slot.error();
    Recording recording(*device_, std::make_unique<Recording::Native>(Recording::Native{std::move(slot).value()}));
    return guard("Vulkan recording", [&]() -> Result<Recording> {
        const vk::raii::CommandBuffer& cmd = recording.native_->slot.cmd;
        cmd.reset();
        cmd.begin({.flags = vk::CommandBufferUsageFlagBits::eOneTimeSubmit});
        if (const auto& pool = device.timestamp_pool(); static_cast<VkQueryPool>(*pool) != VK_NULL_HANDLE) {
            cmd.resetQueryPool(*pool, 0, 2);
        }
        return std::move(recording);
    });
}

Result<Submission> Queue::submit(Recording recording) const {
    assert(recording.device_ == device_ && "a recording of this queue's device");
    assert(!recording.borrowed_ && "a borrowed command buffer is the application's to submit");
    return guard("Vulkan submission", [&]() -> Result<Submission> {
        gpu::VulkanContext& device = gpu::vulkan(*device_);
        gpu::CommandSlot& slot = recording.native_->slot;
        slot.cmd.end();
        device.device().resetFences(*slot.fence);
        const vk::CommandBuffer cmd = *slot.cmd;
        device.queue().submit(vk::SubmitInfo{.commandBufferCount = 1, .pCommandBuffers = &cmd}, *slot.fence);
        device.count_submission();
        return Submission(std::move(recording));
    });
}

void barrier(Recording& recording, Stage before, Stage after) {
    const Access src = source(before);
    const Access dst = destination(after);
    const vk::MemoryBarrier memory{.srcAccessMask = src.access, .dstAccessMask = dst.access};
    gpu::vk_commands(recording).pipelineBarrier(src.stages, dst.stages, {}, memory, {}, {});
}

void copy(Recording& recording, const Buffer& source, std::uint64_t source_offset, const Buffer& target,
          std::uint64_t target_offset, std::uint64_t bytes) {
    gpu::vk_commands(recording).copyBuffer(gpu::vk_buffer(source), gpu::vk_buffer(target),
                                  vk::BufferCopy{.srcOffset = source_offset, .dstOffset = target_offset, .size = bytes});
}

Result<StagingRing> StagingRing::create(const Device& device, std::uint64_t bytes_per_frame, std::uint32_t frames) {
    assert(frames >= 1);
    StagingRing ring;
    ring.bytes_per_frame_ = std::max<std::uint64_t>(bytes_per_frame, 16);
    for (std::uint32_t f = 0; f < frames; ++f) {
        auto slot = Buffer::create(device, ring.bytes_per_frame_, Usage::Upload);
        if (!slot) return slot.error();
        ring.slots_.push_back(std::move(slot).value());
    }
    return ring;
}

void StagingRing::next_frame() {
    current_ = (current_ + 1) % static_cast<std::uint32_t>(slots_.size());
    used_ = 0;
}

Result<std::pair<const Buffer*, std::uint64_t>> StagingRing::write(std::span<const std::byte> bytes) {
    const std::uint64_t rounded = (bytes.size() + 15) / 16 * 16;
    if (used_ + rounded > bytes_per_frame_) {
        return make_error(Error::Kind::InvalidInput, "a frame uploads more than the " + std::to_string(bytes_per_frame_) +
                                                         " bytes of input its staging slot holds");
    }
    const Buffer& slot = slots_[current_];
    std::memcpy(slot.mapped() + used_, bytes.data(), bytes.size());
    const std::uint64_t offset = used_;
    used_ += rounded;
    return std::pair<const Buffer*, std::uint64_t>{&slot, offset};
}

Result<void> upload(Recording& recording, const Buffer& buffer, std::span<const std::byte> bytes) {
    assert(bytes.size() <= buffer.size());
    if (bytes.empty()) return {};
    if (recording.borrowed()) {
        // Frames in flight may still read the buffer: write it on the GPU, in order.
        assert(recording.staging() != nullptr && "a borrowed recording that uploads needs a staging ring");
        auto source = recording.staging()->write(bytes);
        if (!source) return source.error();
        barrier(recording, Stage::Compute | Stage::Transfer, Stage::Transfer);
        copy(recording, *source.value().first, source.value().second, buffer, 0, bytes.size());
        barrier(recording, Stage::Transfer, Stage::Compute);
        return {};
    }
    if (buffer.mapped() != nullptr) {
        std::memcpy(buffer.mapped(), bytes.data(), bytes.size());
        return {};
    }
    auto staging = Buffer::create(recording.device(), bytes.size(), Usage::Upload);
    if (!staging) return staging.error();
    std::memcpy(staging.value().mapped(), bytes.data(), bytes.size());
    // Earlier kernels of this recording may still read (or write) the buffer.
    barrier(recording, Stage::Compute, Stage::Transfer);
    copy(recording, staging.value(), 0, buffer, 0, bytes.size());
    // The kernels read what the copy wrote.
    barrier(recording, Stage::Transfer, Stage::Compute);
    recording.keep(std::move(staging).value());
    return {};
}

Result<void> upload(Device& device, const Buffer& buffer, std::span<const std::byte> bytes) {
    if (bytes.empty()) return {};
    if (buffer.mapped() != nullptr) {
        assert(bytes.size() <= buffer.size());
        std::memcpy(buffer.mapped(), bytes.data(), bytes.size());
        return {};
    }
    const Queue queue(device);
    auto recording = queue.begin();
    if (!recording) return recording.error();
    KW_TRY(upload(recording.value(), buffer, bytes));
    auto submission = queue.submit(std::move(recording).value());
    if (!submission) return submission.error();
    return submission.value().wait();
}

Result<void> download(Device& device, const Buffer& buffer, std::span<std::byte> bytes) {
    assert(bytes.size() <= buffer.size());
    if (bytes.empty()) return {};
    gpu::vulkan(device).count_read_back(bytes.size());
    if (buffer.mapped() != nullptr) {
        KW_TRY(buffer.invalidate(device));
        std::memcpy(bytes.data(), buffer.mapped(), bytes.size());
        return {};
    }
    auto staging = Buffer::create(device, bytes.size(), Usage::Readback);
    if (!staging) return staging.error();
    const Queue queue(device);
    auto recording = queue.begin();
    if (!recording) return recording.error();
    // The kernels wrote what the copy reads; the host then reads the copy.
    barrier(recording.value(), Stage::Compute, Stage::Transfer);
    copy(recording.value(), buffer, 0, staging.value(), 0, bytes.size());
    barrier(recording.value(), Stage::Transfer, Stage::Host);
    auto submission = queue.submit(std::move(recording).value());
    if (!submission) return submission.error();
    KW_TRY(submission.value().wait());
    KW_TRY(staging.value().invalidate(device));
    std::memcpy(bytes.data(), staging.value().mapped(), bytes.size());
    return {};
}

}  // namespace kodawari::compute

namespace kodawari::gpu {

compute::Recording borrow(compute::Device& device, VkCommandBuffer cmd, compute::StagingRing* staging) {
    auto native = std::make_unique<compute::Recording::Native>();
    // No pool: the command buffer is let go of, never freed (Recording::release()).
    native->slot.cmd = vk::raii::CommandBuffer(vulkan(device).device(), cmd, VK_NULL_HANDLE);
    return compute::Recording::borrow(device, std::move(native), staging);
}

}  // namespace kodawari::gpu
