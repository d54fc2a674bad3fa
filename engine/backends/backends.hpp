#pragma once
// Constructors of the CPU backends (kodawari::sim), used by make_cpu_bird_backend() and
// make_cpu_rod_backend(); the vulkan ones are in device_backends.hpp.

#include <memory>

#include "kodawari/backend.hpp"
#include "kodawari/rod_backend.hpp"

namespace kodawari {

[[nodiscard]] std::unique_ptr<BirdBackend> new_cpu_bird_backend(bool reference, unsigned threads);
[[nodiscard]] std::unique_ptr<RodBackend> new_cpu_rod_backend(bool reference, unsigned threads);

}  // namespace kodawari
