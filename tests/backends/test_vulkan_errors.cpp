// Errors that keep what caused them (issue 19): the one boundary where vulkan.hpp's
// exceptions become Errors (gpu::guard, also named compute::guard) keeps the VkResult and
// names the operation, and a device selection that passes over every device says why
// for each one, as vk-bootstrap's errors do. The boundary is internal to the engine, so
// this file is compiled as the engine's sources are (tests/CMakeLists.txt).
#include <gtest/gtest.h>

#include <string>

#include "gpu/compute_vulkan.hpp"
#include "gpu/vulkan_context.hpp"
#include "kodawari/vulkan/gpu_info.hpp"
#include "test_support.hpp"

using namespace kodawari;

namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(VulkanErrors, GuardKeepsTheVkResultAndNamesTheOperation) {
    const auto failed = gpu::guard("Vulkan buffer of 64 bytes", []() -> Result<int> {
        throw vk::OutOfDeviceMemoryError("vkAllocateMemory");
    });
    ASSERT_FALSE(failed.ok());
    EXPECT_EQ(failed.error().kind, Error::Kind::Vulkan);
    EXPECT_EQ(failed.error().vk_result, VK_ERROR_OUT_OF_DEVICE_MEMORY);
    EXPECT_TRUE(contains(failed.error().message, "Vulkan buffer of 64 bytes")) << failed.error().message;
    EXPECT_TRUE(contains(failed.error().message, "vkAllocateMemory")) << failed.error().message;
    EXPECT_TRUE(failed.error().rejected_devices.empty());
}

TEST(VulkanErrors, ComputeGuardIsTheSameBoundary) {
    const auto passed = compute::guard("Vulkan nothing", []() -> Result<int> { return 7; });
    ASSERT_TRUE(passed.ok());
    EXPECT_EQ(passed.value(), 7);
    const auto lost = compute::guard("Vulkan submission", []() -> Result<void> { throw vk::DeviceLostError("vkQueueSubmit"); });
    ASSERT_FALSE(lost.ok());
    EXPECT_EQ(lost.error().kind, Error::Kind::Vulkan);
    EXPECT_EQ(lost.error().vk_result, VK_ERROR_DEVICE_LOST);
    EXPECT_TRUE(contains(lost.error().message, "Vulkan submission")) << lost.error().message;
}

// A swapchain out of date is control flow for the renderer: it tells it apart by the code.
TEST(VulkanErrors, OutOfDateKeepsItsCode) {
    const auto stale = gpu::guard("Vulkan present", []() -> Result<bool> { throw vk::OutOfDateKHRError("vkQueuePresentKHR"); });
    ASSERT_FALSE(stale.ok());
    EXPECT_EQ(stale.error().vk_result, VK_ERROR_OUT_OF_DATE_KHR);
}

// The command line's "no Vulkan driver found" (tests/cli_test.sh) comes from here; the
// machine's setup, not a failed call, so Unsupported, but the code is kept.
TEST(VulkanErrors, NoDriverSaysWhatToInstallAndKeepsTheCode) {
    const auto none = gpu::guard("Vulkan instance", []() -> Result<void> { throw vk::IncompatibleDriverError("vkCreateInstance"); });
    ASSERT_FALSE(none.ok());
    EXPECT_EQ(none.error().kind, Error::Kind::Unsupported);
    EXPECT_EQ(none.error().vk_result, VK_ERROR_INCOMPATIBLE_DRIVER);
    EXPECT_TRUE(contains(none.error().message, "no Vulkan driver found")) << none.error().message;
}

TEST(VulkanErrors, ADeviceNameThatMatchesNothingNamesEveryDeviceAndWhy) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    const auto all = list_gpus("");
    ASSERT_TRUE(all.ok());
    const std::string request = "no-such-device-kodawari";
    const auto ctx = gpu::VulkanContext::create({.device = request});
    ASSERT_FALSE(ctx.ok());
    const Error& error = ctx.error();
    // The caller's request names nothing there: bad input (the command line's exit 2).
    EXPECT_EQ(error.kind, Error::Kind::InvalidInput);
    EXPECT_EQ(error.vk_result, 0) << "no Vulkan call failed: every device was passed over";
    ASSERT_EQ(error.rejected_devices.size(), all.value().devices.size());
    for (std::size_t i = 0; i < error.rejected_devices.size(); ++i) {
        const std::string& rejection = error.rejected_devices[i];
        EXPECT_TRUE(contains(rejection, all.value().devices[i].name + ": ")) << rejection;
        // A device the engine can use is passed over for the name; one it cannot, for its own reason.
        if (all.value().devices[i].rejected.empty()) {
            EXPECT_TRUE(contains(rejection, "does not match \"" + request + "\"")) << rejection;
        }
        EXPECT_TRUE(contains(error.message, rejection)) << error.message;
    }
    EXPECT_TRUE(contains(error.message, "no usable Vulkan device matches \"" + request + "\"")) << error.message;
}

TEST(VulkanErrors, AnIndexOutOfRangeMarksEveryDeviceInTheList) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    const auto listed = list_gpus("99");
    ASSERT_TRUE(listed.ok()) << listed.error().message;
    const GpuInventory& inventory = listed.value();
    EXPECT_EQ(inventory.chosen, -1);
    for (const GpuDeviceInfo& d : inventory.devices) {
        ASSERT_FALSE(d.rejected.empty()) << d.name;
        if (d.has_compute_queue && !contains(d.rejected, "needed")) {
            EXPECT_EQ(d.rejected, "is device " + std::to_string(d.index) + ", not 99");
        }
        EXPECT_TRUE(contains(inventory.reason, d.name + ": " + d.rejected)) << inventory.reason;
    }
    // The device a request does pick is not marked.
    const auto best = list_gpus("");
    ASSERT_TRUE(best.ok());
    if (best.value().chosen >= 0) {
        EXPECT_TRUE(best.value().devices[static_cast<std::size_t>(best.value().chosen)].rejected.empty());
    }
}

}  // namespace
