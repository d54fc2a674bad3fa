#include <algorithm>
#include <cstdio>
#include <vector>

#include "commands.hpp"
#include "kodawari/compare.hpp"
#include "kodawari/scene.hpp"

namespace kodawari::cli {

int cmd_validate(Args args) {
    BackendChoice choice = read_backend_choice(args);
    if (choice.backend == "auto") choice.backend = "vulkan";
    if (choice.backend == "cpu-reference") throw UsageError{"validate compares a backend against cpu-reference; choose vulkan or cpu"};
    const auto frames_option = args.count("frames", 1, 10'000'000);
    auto loaded = load_scene_arguments(args.positionals(), "validate", frames_option);
    if (!loaded) return report(loaded.error());
    const Scene& scene = loaded.value().scene;
    birds::BirdWorld& world = loaded.value().world;

    auto tested = open_backend(choice);
    if (!tested) return report(tested.error());
    auto reference = make_bird_backend(BackendKind::CpuReference, {});
    if (!reference) return report(reference.error());
    if (auto r = tested.value()->load(world); !r) return report(r.error());
    if (auto r = reference.value()->load(world); !r) return report(r.error());

    const std::size_t count = world.birds.size();
    const std::uint32_t chunk = static_cast<std::uint32_t>(std::clamp<std::size_t>((1u << 19) / count, 1, 120));
    std::vector<gpu::BirdPose> ref_poses, test_poses;
    std::vector<gpu::BirdDiag> ref_diag, test_diag;
    BirdComparison comparison(world);
    for (std::uint32_t done = 0; done < world.frames;) {
        const std::uint32_t n = std::min(chunk, world.frames - done);
        for (auto* v : {&ref_poses, &test_poses}) v->resize(std::size_t{n} * count);
        for (auto* v : {&ref_diag, &test_diag}) v->resize(std::size_t{n} * count);
        if (auto r = reference.value()->simulate(n, {ref_poses, ref_diag}); !r) return report(r.error());
        if (auto r = tested.value()->simulate(n, {test_poses, test_diag}); !r) return report(r.error());
        comparison.add(done, n, ref_poses, test_poses, ref_diag, test_diag);
        done += n;
        if (stderr_is_terminal()) progress("validating", done, world.frames);
    }

    std::printf("validate \"%s\": %s on %s vs cpu-reference, %zu birds x %u frames\n", scene.name.c_str(),
                std::string(tested.value()->name()).c_str(), tested.value()->device().c_str(), count, world.frames);
    std::printf("%-20s %-4s %12s %12s %12s  %s\n", "quantity", "unit", "max", "mean", "tolerance", "worst (bird, frame)");
    for (const Deviation& d : comparison.results()) {
        std::printf("%-20s %-4s %12.3e %12.3e %12.3e  (%u, %u) %s\n", d.quantity.c_str(), d.unit.c_str(), d.max, d.mean, d.tolerance,
                    d.worst_bird, d.worst_frame, d.within() ? "ok" : "OVER TOLERANCE");
    }
    const std::uint32_t messages = tested.value()->validation_messages();
    if (messages > 0) std::printf("Vulkan validation messages: %u\n", messages);
    const bool ok = comparison.within() && messages == 0;
    std::printf("%s\n", ok ? "validate: PASS" : "validate: FAIL");
    return ok ? kExitOk : kExitFailure;
}

}  // namespace kodawari::cli
