// Kernel statistics (BackendOptions::kernel_statistics, compute::Device::kernel_statistics;
// issue 38 item 2): a device opened to capture them lists every kernel created on it with
// the driver's figures (NVIDIA's register count and spills) where the driver offers
// VK_KHR_pipeline_executable_properties, and says which is missing where it does not: the
// extension (Mesa 22's lavapipe, this project's CI) or the request. The first branch runs
// only on a driver with the extension; on lavapipe the second.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include <kodawari/shared/rods.h>

#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/rods/synthetic.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/vulkan/compute.hpp"
#include "test_support.hpp"

using namespace kodawari;

TEST(KernelStatistics, ListedWhereTheDriverOffersThemAndWhyNotElsewhere) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    BackendOptions options = testing_support::gpu_options();
    options.kernel_statistics = true;
    auto device = open_shared_device(options);
    ASSERT_TRUE(device.ok()) << device.error().message;
    options.context = device.value();
    rods::SyntheticOptions synthetic;
    synthetic.chains = 37;
    synthetic.joints = 4;
    synthetic.settle = false;
    auto scene = rods::SyntheticScene::make(synthetic);
    ASSERT_TRUE(scene.ok());
    auto backend = make_rod_backend(BackendKind::Vulkan, options);
    ASSERT_TRUE(backend.ok()) << backend.error().message;
    rods::RodFrame frame;
    scene.value().frame(0, 1.0f / 60.0f, frame);
    ASSERT_TRUE(backend.value()->load(scene.value().world(), frame).ok());
    scene.value().frame(1, 1.0f / 60.0f, frame);
    ASSERT_TRUE(backend.value()->step(frame).ok());

    auto statistics = device.value()->kernel_statistics();
    if (statistics.ok()) {
        std::printf("%s: %zu kernels with statistics\n", device.value()->info().name.c_str(), statistics.value().size());
        ASSERT_FALSE(statistics.value().empty());
        const compute::KernelStatistics& k = statistics.value().front();
        EXPECT_EQ(k.kernel, "rods_step");
        EXPECT_EQ(k.specialization.size(), std::size_t{KW_RODS_SPEC_COUNT});
        EXPECT_FALSE(k.values.empty()) << k.note;
        for (const auto& v : k.values) std::printf("  %s: %s = %s\n", v.executable.c_str(), v.name.c_str(), v.value.c_str());
    } else {
        std::printf("%s\n", statistics.error().message.c_str());
        EXPECT_EQ(statistics.error().kind, Error::Kind::Unsupported);
        EXPECT_NE(statistics.error().message.find("VK_KHR_pipeline_executable_properties"), std::string::npos)
            << statistics.error().message;
        EXPECT_NE(statistics.error().message.find(device.value()->info().name), std::string::npos) << statistics.error().message;
    }
    EXPECT_EQ(device.value()->validation_messages(), 0u);

    // A device opened without the option says so.
    BackendOptions plain = testing_support::gpu_options();
    auto other = open_shared_device(plain);
    ASSERT_TRUE(other.ok()) << other.error().message;
    auto none = other.value()->kernel_statistics();
    ASSERT_FALSE(none.ok());
    EXPECT_NE(none.error().message.find("BackendOptions::kernel_statistics"), std::string::npos) << none.error().message;
}
