// A bird backend of the test's parameter beside cpu-reference, for tests that run one body
// against every backend (tests/backends/test_backends.cpp, tests/birds/test_route_motion.cpp):
// vulkan skips only where no Vulkan device exists, and a backend that reported validation
// messages fails its test.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "kodawari/backends/backend.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "test_support.hpp"

namespace kodawari::testing_support {

class BirdBackendTest : public ::testing::TestWithParam<BackendCase> {
protected:
    void SetUp() override {
        if (GetParam() == BackendKind::Vulkan) {
            if (const std::string why = no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
        }
        auto made = make_bird_backend(GetParam(), backend_options(GetParam()));
        ASSERT_TRUE(made.ok()) << made.error().message;
        backend_ = std::move(made).value();
        reference_ = std::move(make_bird_backend(BackendKind::CpuReference, {})).value();
    }
    void TearDown() override {
        if (backend_) {
            EXPECT_EQ(backend_->validation_messages(), 0u) << "Vulkan validation reported problems (see stderr)";
        }
    }

    std::unique_ptr<BirdBackend> backend_;    ///< the parameter's
    std::unique_ptr<BirdBackend> reference_;  ///< cpu-reference
};

}  // namespace kodawari::testing_support
