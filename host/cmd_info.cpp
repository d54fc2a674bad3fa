#include <cstdio>
#include <thread>

#include "kodawari/core/version.hpp"
#include "commands.hpp"
#include "kodawari/vulkan/gpu_info.hpp"
#include "kodawari/backends/simd.hpp"

namespace kodawari::cli {

namespace {

struct InfoOptions {
    std::optional<std::string> device;
    std::optional<std::string> isa;
};

int cmd_info(const InfoOptions& o) {
    const std::string device = o.device.value_or(env_text("KODAWARI_DEVICE"));
    const std::string requested_isa = o.isa.value_or(env_text("KODAWARI_ISA"));
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
    // info prints everything it can, then exits 2 when what it was asked to describe (an
    // instruction set, a device) is not there, as every command does for bad input.
    const int asked_isa_status = isa ? kExitOk : kExitBadInput;
    auto inventory = list_gpus(device);
    if (!inventory) {
        std::printf("Vulkan: unavailable: %s\n", inventory.error().message.c_str());
        std::printf("backend auto: cpu\n");
        return asked_isa_status;
    }
    const auto& inv = inventory.value();
    std::printf("Vulkan devices: %zu\n", inv.devices.size());
    for (const auto& d : inv.devices) {
        std::printf("  [%u] %s\n", d.index, d.name.c_str());
        std::printf("      type %s, driver %s, Vulkan %s\n", d.type.c_str(), d.driver.c_str(), d.api_version.c_str());
        std::printf("      compute queue %s, timestamps %s, subgroup %u, workgroup invocations <= %u, groups <= %u x %u x %u\n",
                    d.has_compute_queue ? "yes" : "no", d.timestamps ? "yes" : "no", d.subgroup_size, d.max_workgroup_invocations,
                    d.max_workgroup_count[0], d.max_workgroup_count[1], d.max_workgroup_count[2]);
        std::printf("      storage buffer range %.1f MiB, push constants %u B, shared memory %u KiB, device-local memory %.1f GiB\n",
                    static_cast<double>(d.max_storage_buffer_range) / (1 << 20), d.max_push_constants, d.max_shared_memory / 1024,
                    static_cast<double>(d.device_local_bytes) / (1 << 30));
        // Why it cannot be chosen (an old driver, no compute queue, not the one asked
        // for), so that "chosen: none" is not the only clue.
        if (!d.rejected.empty()) std::printf("      passed over: %s\n", d.rejected.c_str());
    }
    if (inv.chosen >= 0) {
        std::printf("chosen: [%u] %s, because %s\n", inv.devices[static_cast<std::size_t>(inv.chosen)].index,
                    inv.devices[static_cast<std::size_t>(inv.chosen)].name.c_str(), inv.reason.c_str());
        // auto passes over a CPU-type device it was not asked for (issue 38).
        const std::string passed_over = device.empty() ? auto_passes_over(inv.devices[static_cast<std::size_t>(inv.chosen)]) : "";
        if (passed_over.empty()) {
            std::printf("backend auto: vulkan\n");
        } else {
            std::printf("backend auto: cpu (%s)\n", passed_over.c_str());
        }
    } else if (!device.empty()) {
        std::printf("chosen: none: %s\nbackend auto: none (a device was asked for: the simulating commands exit 2)\n",
                    inv.reason.c_str());
        return kExitBadInput;
    } else {
        std::printf("chosen: none: %s\nbackend auto: cpu\n", inv.reason.c_str());
    }
    return asked_isa_status;
}

}  // namespace

Command add_info(CLI::App& app) {
    auto o = std::make_shared<InfoOptions>();
    CLI::App* c = app.add_subcommand("info", "version, Vulkan devices and which one is chosen, CPU threads and SIMD instruction sets");
    add_text(*c, "--device", o->device, "NAME|INDEX",
             "the device to choose, as the simulating commands' --device (default: $KODAWARI_DEVICE)");
    add_text(*c, "--isa", o->isa, "avx512|avx2|sse4|scalar",
             "the SIMD instruction set to describe, as the simulating commands' --isa (default: $KODAWARI_ISA, else the widest)");
    return {c, [o] { return cmd_info(*o); }};
}

}  // namespace kodawari::cli
