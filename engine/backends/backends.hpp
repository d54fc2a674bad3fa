#pragma once
// Constructors of the concrete backends, used by make_bird_backend() and make_rod_backend().

#include <memory>

#include "kodawari/backend.hpp"
#include "kodawari/rod_backend.hpp"

namespace kodawari {

[[nodiscard]] std::unique_ptr<BirdBackend> make_cpu_bird_backend(bool reference, unsigned threads);
[[nodiscard]] Result<std::unique_ptr<BirdBackend>> make_vulkan_bird_backend(const BackendOptions& options);
[[nodiscard]] std::unique_ptr<RodBackend> make_cpu_rod_backend(bool reference, unsigned threads);
[[nodiscard]] Result<std::unique_ptr<RodBackend>> make_vulkan_rod_backend(const BackendOptions& options);

}  // namespace kodawari
