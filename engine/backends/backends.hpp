#pragma once
// Constructors of the concrete backends, used by make_bird_backend().

#include <memory>

#include "kodawari/backend.hpp"

namespace kodawari {

[[nodiscard]] std::unique_ptr<BirdBackend> make_cpu_bird_backend(bool reference, unsigned threads);
[[nodiscard]] Result<std::unique_ptr<BirdBackend>> make_vulkan_bird_backend(const BackendOptions& options);

}  // namespace kodawari
