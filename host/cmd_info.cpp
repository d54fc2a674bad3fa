#include <cstdio>
#include <thread>

#include "kodawari/version.hpp"
#include "commands.hpp"
#include "kodawari/gpu_info.hpp"
#include "kodawari/simd.hpp"

namespace kodawari::cli {

int cmd_info(Args args) {
    std::string device = env_text("KODAWARI_DEVICE");
    if (auto d = args.option("device")) device = *d;
    std::string requested_isa = env_text("KODAWARI_ISA");
    if (auto i = args.option("isa")) requested_isa = *i;
    if (!args.positionals().empty()) throw UsageError{"info takes no arguments"};
    std::printf("kodawari %s\n", std::string(version()).c_str());
    std::printf("CPU threads: %u (the cpu backend's default)\n", std::thread::hardware_concurrency());
    std::string available;
    for (const std::string& name : available_simd_isas()) available += (available.empty() ? "" : ", ") + name;
    const auto isa = simd_isa(requested_isa);
    if (isa) {
        std::printf("SIMD: %s (the cpu backend's, %u floats per vector%s); available: %s\n", isa.value().c_str(),
                    simd_lanes(isa.value()), requested_isa.empty() ? ", the widest" : ", as asked", available.c_str());
    } else {
        std::printf("SIMD: %s\n", isa.error().message.c_str());
    }
    auto inventory = list_gpus(device);
    if (!inventory) {
        std::printf("Vulkan: unavailable: %s\n", inventory.error().message.c_str());
        std::printf("backend auto: cpu\n");
        return kExitOk;
    }
    const auto& inv = inventory.value();
    std::printf("Vulkan devices: %zu\n", inv.devices.size());
    for (const auto& d : inv.devices) {
        std::printf("  [%u] %s\n", d.index, d.name.c_str());
        std::printf("      type %s, driver %s, Vulkan %s\n", d.type.c_str(), d.driver.c_str(), d.api_version.c_str());
        std::printf("      compute queue %s, timestamps %s, subgroup %u, workgroup invocations <= %u, groups <= %u x %u x %u\n",
                    d.has_compute_queue ? "yes" : "no", d.timestamps ? "yes" : "no", d.subgroup_size, d.max_workgroup_invocations,
                    d.max_workgroup_count[0], d.max_workgroup_count[1], d.max_workgroup_count[2]);
        std::printf("      storage buffer range %.1f MiB, push constants %u B, device-local memory %.1f GiB\n",
                    static_cast<double>(d.max_storage_buffer_range) / (1 << 20), d.max_push_constants,
                    static_cast<double>(d.device_local_bytes) / (1 << 30));
        // Why it cannot be chosen (an old driver, no compute queue, not the one asked
        // for), so that "chosen: none" is not the only clue.
        if (!d.rejected.empty()) std::printf("      passed over: %s\n", d.rejected.c_str());
    }
    if (inv.chosen >= 0) {
        std::printf("chosen: [%u] %s, because %s\n", inv.devices[static_cast<std::size_t>(inv.chosen)].index,
                    inv.devices[static_cast<std::size_t>(inv.chosen)].name.c_str(), inv.reason.c_str());
        std::printf("backend auto: vulkan\n");
    } else {
        std::printf("chosen: none: %s\nbackend auto: cpu\n", inv.reason.c_str());
    }
    return kExitOk;
}

}  // namespace kodawari::cli
