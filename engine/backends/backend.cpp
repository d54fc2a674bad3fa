// The CPU kinds' factories (kodawari::sim); make_bird_backend() and the others, which also
// make vulkan backends, are in backend_factory.cpp (kodawari::vulkan).
#include "backends/backends.hpp"
#include "backends/pose_backends.hpp"
#include "core/parallel.hpp"

namespace kodawari {

std::string_view backend_name(BackendKind kind) {
    switch (kind) {
        case BackendKind::CpuReference: return "cpu-reference";
        case BackendKind::Cpu: return "cpu";
        case BackendKind::Vulkan: return "vulkan";
    }
    return "cpu-reference";
}

unsigned cpu_backend_threads(const BackendOptions& options) { return resolve_threads(options.threads); }

Result<void> BirdBackend::check_motion(const birds::BirdWorld& world, std::uint32_t frames) const {
    const std::uint64_t needed = std::uint64_t{frames} * world.driven;
    if (motion_.size() >= needed) return {};
    return make_error(Error::Kind::InvalidInput, std::to_string(world.driven) + " birds are flown by another domain: drive() must give " +
                                                     std::to_string(needed) + " motions for " + std::to_string(frames) +
                                                     " frames, got " + std::to_string(motion_.size()));
}

namespace {

Error no_vulkan(std::string_view family) {
    return make_error(Error::Kind::InvalidInput,
                      "the vulkan " + std::string(family) +
                          " backend is in kodawari::vulkan: link it and call make_" + std::string(family) +
                          "_backend() (kodawari/vulkan/backend_factory.hpp)");
}

}  // namespace

Result<std::unique_ptr<BirdBackend>> make_cpu_bird_backend(BackendKind kind, const BackendOptions& options) {
    switch (kind) {
        case BackendKind::CpuReference: return new_reference_bird_backend();
        case BackendKind::Cpu: {
            auto isa = simd::choose_isa(options.isa);
            if (!isa) return isa.error();
            return new_simd_bird_backend(std::move(isa).value(), cpu_backend_threads(options));
        }
        case BackendKind::Vulkan: return no_vulkan("bird");
    }
    return make_error(Error::Kind::Internal, "unknown backend");
}

Result<std::unique_ptr<RodBackend>> make_cpu_rod_backend(BackendKind kind, const BackendOptions& options) {
    switch (kind) {
        case BackendKind::CpuReference: return new_reference_rod_backend();
        case BackendKind::Cpu: {
            auto isa = simd::choose_isa(options.isa);
            if (!isa) return isa.error();
            return new_simd_rod_backend(std::move(isa).value(), cpu_backend_threads(options));
        }
        case BackendKind::Vulkan: return no_vulkan("rod");
    }
    return make_error(Error::Kind::Internal, "unknown backend");
}

Result<std::unique_ptr<PoseBackend>> make_cpu_pose_backend(BackendKind kind, const BackendOptions& options) {
    switch (kind) {
        case BackendKind::CpuReference: return new_reference_pose_backend();
        case BackendKind::Cpu: {
            auto isa = simd::choose_isa(options.isa);
            if (!isa) return isa.error();
            return new_simd_pose_backend(std::move(isa).value(), cpu_backend_threads(options));
        }
        case BackendKind::Vulkan: return no_vulkan("pose");
    }
    return make_error(Error::Kind::Internal, "unknown backend");
}

}  // namespace kodawari
