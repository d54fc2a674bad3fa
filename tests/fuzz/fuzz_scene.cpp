// Fuzz target: the scene loader (docs/scene-format.md, versions 1 and 2) and what a
// loaded scene goes on to: its worlds built and three frames simulated on the cpu
// backend. Inputs are scene files; the path handed to the loader lies in scenes/, so
// the shipped scenes' references (characters/chibi.glb) resolve as they do for users.
//
// Invariants (a crash, sanitizer report or finding() otherwise):
// - any input loads or is rejected with a message that names the file;
// - a scene that loads and is small enough to simulate here (the harness's bound: at
//   most 2 000 birds and 48 character instances, so that each input runs in
//   milliseconds) simulates without error and gives finite bird poses and chain states.
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_support.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "test_paths.hpp"

namespace {

constexpr std::uint64_t kMaxBirds = 2000;
constexpr std::uint64_t kMaxInstances = 48;

std::uint64_t instance_total(const kodawari::Scene& scene) {
    if (scene.crowds.empty()) return scene.characters.size();
    std::uint64_t n = 0;
    for (const auto& c : scene.crowds) n += std::uint64_t{c.count} + c.instances.size();
    return n;
}

std::uint64_t bird_total(const kodawari::Scene& scene) {
    std::uint64_t n = 0;
    for (const auto& f : scene.flocks) n += f.count;
    return n;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace kodawari;
    const std::string path = std::string(KODAWARI_SOURCE_DIR) + "/scenes/fuzz-input.json";
    auto scene = parse_scene(std::string(reinterpret_cast<const char*>(data), size), path);
    if (!scene) {
        if (scene.error().message.find(path) == std::string::npos) {
            fuzz::finding("the error does not name the file: " + scene.error().message);
        }
        return 0;
    }
    if (bird_total(scene.value()) > kMaxBirds || instance_total(scene.value()) > kMaxInstances) return 0;

    constexpr std::uint32_t kFrames = 3;
    SimulationOptions options;
    options.backend = BackendKind::Cpu;
    options.options.threads = 1;  // a thread pool per input would cost more than the input
    options.frames = kFrames;
    auto sim = Simulation::create(std::move(scene).value(), options);
    if (!sim) return 0;  // a character file that does not load, a route that does not build: messages
    const std::size_t bird_count = bird_world(*sim.value()).birds.size();
    std::vector<gpu::BirdPose> poses(bird_count);
    for (std::uint32_t f = 0; f < kFrames; ++f) {
        auto stepped = step_birds(*sim.value(), 1, poses);
        if (!stepped) fuzz::finding("a loaded scene failed to step: " + stepped.error().message);
        for (const gpu::BirdPose& p : poses) {
            fuzz::require_finite(p.position.x + p.position.y + p.position.z, "a bird position");
            for (const gpu::vec4& q : p.rotation) fuzz::require_finite(q.x + q.y + q.z + q.w, "a bird rotation");
        }
    }
    if (rod_scene(*sim.value()) != nullptr) {
        ChainSnapshot chains;
        auto read = read_chains(*sim.value(), chains);
        if (!read) fuzz::finding("reading the chains failed: " + read.error().message);
        for (const auto& p : chains.positions) {
            for (int c = 0; c < 3; ++c) fuzz::require_finite(p[c], "a chain joint position");
        }
    }
    return 0;
}
