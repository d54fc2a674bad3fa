// A program built against an installed (or add_subdirectory()'d) Kodawari, the way an
// application would: tests/package/run_consumers.sh builds it with find_package, with
// pkg-config and with add_subdirectory. It includes a public header of every component
// and calls into each, so that a header, a dependency or a symbol missing from the
// package fails the build or the link, and it runs something real with each:
//
//   sim     a rod world stepped on the cpu backend (inextensible chains), birds flown
//   vulkan  the backend factory, and the Vulkan device list (a machine without a device is fine)
//   io      a scene file loaded, the project's glTF character imported (tinygltf), a GLB written
//   render  a PNG written (stb), a camera's projection
//   engine  Simulation on the cpu backend: a scene file simulated, its chains read back
//
//   consumer SOURCE_DIR OUT_DIR
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/glm.hpp>

// sim
#include <kodawari/backends/backend.hpp>
#include <kodawari/backends/rod_backend.hpp>
#include <kodawari/rods/synthetic.hpp>
#include <kodawari/core/version.hpp>
// vulkan
#include <kodawari/vulkan/backend_factory.hpp>
#include <kodawari/vulkan/gpu_info.hpp>
// io
#include <kodawari/export/export.hpp>
#include <kodawari/gltf/import.hpp>
#include <kodawari/scene/scene.hpp>
// render
#include <kodawari/render/renderer.hpp>
// engine
#include <kodawari/domains/chains.hpp>
#include <kodawari/simulation/simulation.hpp>

namespace {

using namespace kodawari;

// Built against 0.2 headers: KODAWARI_VERSION_* are compile-time constants.
static_assert(KODAWARI_VERSION_MAJOR == 0 && KODAWARI_VERSION_MINOR == 3, "find_package(kodawari 0.3) gave other headers");

int failures = 0;

void check(bool ok, const std::string& what) {
    if (!ok) {
        std::fprintf(stderr, "consumer: FAILED: %s\n", what.c_str());
        ++failures;
    }
}

template <typename T>
bool ok(const Result<T>& result, const std::string& what) {
    if (!result) check(false, what + ": " + result.error().message);
    return result.ok();
}

bool finite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// sim: a procedural rod world, 30 frames on the cpu backend; the chains stay inextensible.
void rods_on_cpu() {
    rods::SyntheticOptions options;
    options.chains = 5;
    options.joints = 6;
    auto scene = rods::SyntheticScene::make(options);
    if (!ok(scene, "SyntheticScene::make")) return;
    auto backend = make_cpu_rod_backend(BackendKind::Cpu, {});
    if (!ok(backend, "make_cpu_rod_backend")) return;
    rods::RodFrame frame;
    scene.value().frame(0, 1.0f / 60.0f, frame);
    if (!ok(backend.value()->load(scene.value().world(), frame), "rod load")) return;
    for (std::uint32_t f = 1; f <= 30; ++f) {
        scene.value().frame(f, 1.0f / 60.0f, frame);
        if (!ok(backend.value()->step(frame), "rod step")) return;
    }
    ChainSnapshot snapshot;
    if (!ok(backend.value()->read(snapshot), "rod read")) return;
    const rods::RodWorld& world = scene.value().world();
    float worst = 0.0f;
    for (const rods::ChainInstance& chain : world.chains) {
        const rods::Chain& shape = world.templ(chain).chain;
        for (std::uint32_t i = 0; i + 1 < shape.joint_count; ++i) {
            const glm::vec3 a = snapshot.positions[chain.joint_begin + i];
            const glm::vec3 b = snapshot.positions[chain.joint_begin + i + 1];
            check(finite(a) && finite(b), "a joint is not finite");
            worst = std::max(worst, std::abs(glm::length(b - a) - shape.segment_length[i]) / shape.segment_length[i]);
        }
    }
    check(worst < 0.005f, "chains stretched by " + std::to_string(worst) + " of a segment");
    std::printf("consumer: sim: %zu chains x %u joints, 30 frames on %s: max stretch %.2g of a segment\n", world.chains.size(),
                options.joints, std::string(backend.value()->name()).c_str(), static_cast<double>(worst));
}

// sim + io: a scene's flocks flown on the cpu-reference backend, made by the factory
// (kodawari::vulkan), and written as a GLB (kodawari::io).
void fly_birds(const std::string& source_dir, const std::string& out_dir) {
    auto scene = load_scene(source_dir + "/scenes/flock.json");
    if (!ok(scene, "load_scene(flock.json)")) return;
    auto world = build_bird_world(scene.value());
    if (!ok(world, "build_bird_world")) return;
    auto backend = make_bird_backend(BackendKind::CpuReference, {});
    if (!ok(backend, "make_bird_backend")) return;
    if (!ok(backend.value()->load(world.value()), "bird load")) return;
    constexpr std::uint32_t kFrames = 10;
    const std::size_t count = world.value().birds.size();
    std::vector<gpu::BirdPose> poses(kFrames * count);
    if (!ok(backend.value()->simulate(kFrames, {.poses = poses, .diag = {}}), "bird simulate")) return;
    float moved = 0.0f;
    for (std::size_t b = 0; b < count; ++b) {
        const gpu::BirdPose& first = poses[b];
        const gpu::BirdPose& last = poses[(kFrames - 1) * count + b];
        const glm::vec3 p0(first.position.x, first.position.y, first.position.z);
        const glm::vec3 p1(last.position.x, last.position.y, last.position.z);
        check(finite(p0) && finite(p1), "a bird is not finite");
        moved = std::max(moved, glm::length(p1 - p0));
    }
    check(moved > 0.1f, "no bird moved");
    const std::string glb = out_dir + "/flock.glb";
    if (!ok(write_birds_glb(glb, world.value(), poses, kFrames), "write_birds_glb")) return;
    check(std::filesystem::file_size(glb) > 1000, "the GLB is empty");
    std::printf("consumer: io: %zu birds, %u frames on %s, %.1f m flown at most, %s (%ju bytes)\n", count, kFrames,
                std::string(backend.value()->name()).c_str(), static_cast<double>(moved), glb.c_str(),
                static_cast<std::uintmax_t>(std::filesystem::file_size(glb)));
}

// io: the project's own character through tinygltf.
void import_character(const std::string& source_dir) {
    auto chibi = gltf::load_character(source_dir + "/scenes/characters/chibi.glb");
    if (!ok(chibi, "load_character(chibi.glb)")) return;
    check(!chibi.value().nodes.empty() && !chibi.value().meshes.empty(), "the character has no nodes or meshes");
    std::printf("consumer: io: chibi.glb: %zu nodes, %zu meshes, %zu animations\n", chibi.value().nodes.size(),
                chibi.value().meshes.size(), chibi.value().animations.size());
}

// vulkan: the device list (no device is an answer too: the CPU backends need none).
void list_devices() {
    auto inventory = list_gpus("");
    if (inventory)
        std::printf("consumer: vulkan: %zu device(s)\n", inventory.value().devices.size());
    else
        std::printf("consumer: vulkan: no device (%s)\n", inventory.error().message.c_str());
}

// render: a camera's projection and a PNG written through the library's stb.
void write_picture(const std::string& out_dir) {
    const render::CameraView camera{};
    const glm::mat4 vp = render::view_projection(camera, 16.0f / 9.0f);
    const glm::vec4 target = vp * glm::vec4(camera.target, 1.0f);
    check(std::abs(target.x / target.w) < 1e-4f && std::abs(target.y / target.w) < 1e-4f, "the target is not at the centre");
    render::Image image;
    image.width = 8;
    image.height = 4;
    image.rgba.assign(std::size_t{image.width} * image.height * 4, 200);
    const render::Image half = render::downscale(image, 4, 2);
    check(half.width == 4 && half.height == 2 && half.at(1, 1).r == 200, "downscale");
    const std::string png = out_dir + "/picture.png";
    if (!ok(render::write_png(png, image), "write_png")) return;
    check(std::filesystem::file_size(png) > 8, "the PNG is empty");
    std::printf("consumer: render: %s\n", png.c_str());
}

// engine: a scene file on Simulation with the cpu backend.
void simulate_scene(const std::string& source_dir) {
    SimulationOptions options;
    options.backend = BackendKind::Cpu;
    options.frames = 30;
    auto sim = Simulation::open(source_dir + "/scenes/ahoge.json", options);
    if (!ok(sim, "Simulation::open(ahoge.json)")) return;
    if (!ok(sim.value()->step(30), "Simulation::step")) return;
    ChainSnapshot snapshot;
    if (!ok(read_chains(*sim.value(), snapshot), "read_chains")) return;
    check(!snapshot.positions.empty(), "no joints");
    for (const glm::vec3& p : snapshot.positions) check(finite(p), "a joint is not finite");
    std::printf("consumer: engine: scene \"%s\", %u frames on %s (%s): %zu joints\n", sim.value()->scene().name.c_str(),
                sim.value()->frame_count(), std::string(backend_name(sim.value()->backend())).c_str(),
                sim.value()->device().c_str(), snapshot.positions.size());
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: consumer SOURCE_DIR OUT_DIR\n");
        return 2;
    }
    const std::string source_dir = argv[1], out_dir = argv[2];
    check(version() == kHeaderVersion, "library " + std::string(version()) + ", headers " + std::string(kHeaderVersion));
    std::printf("consumer: kodawari %s (headers %d.%d.%d)\n", std::string(version()).c_str(), KODAWARI_VERSION_MAJOR,
                KODAWARI_VERSION_MINOR, KODAWARI_VERSION_PATCH);
    rods_on_cpu();
    fly_birds(source_dir, out_dir);
    import_character(source_dir);
    list_devices();
    write_picture(out_dir);
    simulate_scene(source_dir);
    if (failures) std::fprintf(stderr, "consumer: %d check(s) failed\n", failures);
    else std::printf("consumer: ok\n");
    return failures ? 1 : 0;
}
