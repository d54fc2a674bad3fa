// Kodawari's CPU path from C++, no scene file: three strands on a character that walks
// to the side for a second, simulated by the multithreaded CPU backend. main.c does the
// same through the C API and prints the same numbers.
#include <cstdio>

#include <kodawari/backends/rod_backend.hpp>
#include <kodawari/rods/world.hpp>

using namespace kodawari;

int main() {
    rods::ChainShape strand;  // 8 joints, 2 cm apart, leaning to +X; joint 0 on the root
    for (int i = 0; i < 8; ++i) strand.positions.push_back({0.012f * float(i), 0.016f * float(i), 0.0f});
    rods::default_orientations(strand);  // each joint's +Y along its segment
    auto templ = rods::make_chain_template("strand", strand, {}, {}, 0.004f, 0.001f, rods::SolverParams{});
    if (!templ) return std::fprintf(stderr, "%s\n", templ.error().message.c_str()), 1;

    rods::RodWorld world;  // one template, three chains on one character
    world.templates.push_back(templ.value());
    world.character_count = 1;
    for (int c = 0; c < 3; ++c) world.chains.push_back({.template_index = 0, .character = 0});
    if (auto ok = world.finalize(); !ok) return std::fprintf(stderr, "%s\n", ok.error().message.c_str()), 1;

    rods::RodFrame frame;  // the camera in front, the head at 1.5 m, the roots on it
    frame.camera.position = {0.0f, 1.6f, 2.0f};
    frame.reference = {rods::Transform{{0.0f, 1.5f, 0.0f}}};
    frame.roots.assign(3, rods::Transform{});
    auto backend = make_cpu_rod_backend(BackendKind::Cpu, {});  // the reference's code on threads
    if (!backend) return std::fprintf(stderr, "%s\n", backend.error().message.c_str()), 1;
    for (int f = 0; f <= 60; ++f) {  // frame 0 puts the strands at rest; then 1 s at 60 fps
        for (int c = 0; c < 3; ++c) frame.roots[c].position = {0.5f * float(f) / 60.0f + 0.05f * float(c), 1.6f, 0.0f};
        auto ok = f == 0 ? backend.value()->load(world, frame) : backend.value()->step(frame);
        if (!ok) return std::fprintf(stderr, "%s\n", ok.error().message.c_str()), 1;
    }
    ChainSnapshot snapshot;
    if (auto ok = backend.value()->read(snapshot); !ok) return std::fprintf(stderr, "%s\n", ok.error().message.c_str()), 1;
    for (int c = 0; c < 3; ++c) {
        const glm::vec3 tip = snapshot.positions[world.chains[c].joint_begin + 7];
        std::printf("strand %d tip: %.6f %.6f %.6f\n", c, double{tip.x}, double{tip.y}, double{tip.z});
    }
}
