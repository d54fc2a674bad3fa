// Fuzz target: `kodawari rig`'s path. The input is a glTF file (JSON, or GLB when it
// starts with GLB's magic; a VRM is either): loaded, its chains and colliders found
// (VRM 0.x / 1.0 spring bones, else the name patterns), the scene text written for it,
// and that scene parsed back and its chains built, as `kodawari rig` followed by
// `kodawari run` does. The seeds' external buffers (tests/assets/vrm-springbone/*.bin)
// are copied beside the input so that their references resolve.
//
// Invariants: any input loads or is rejected with a message naming the file; a rig
// scene that is made parses back and builds (the rig writes only what the loader takes).
#include <cstdint>
#include <filesystem>
#include <string>

#include "fuzz_support.hpp"
#include "kodawari/gltf/rig_scene.hpp"
#include "kodawari/scene/scene.hpp"
#include "test_paths.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    namespace fs = std::filesystem;
    const fs::path assets = fs::path(KODAWARI_SOURCE_DIR) / "tests/assets/vrm-springbone";
    for (const char* bin : {"plane_mesh.bin", "sphere_mesh.bin"}) {
        fs::copy_file(assets / bin, kodawari::fuzz::scratch_dir() / bin, fs::copy_options::overwrite_existing);
    }
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace kodawari;
    const bool glb = size >= 4 && data[0] == 'g' && data[1] == 'l' && data[2] == 'T' && data[3] == 'F';
    const std::filesystem::path file = fuzz::scratch_dir() / (glb ? "input.glb" : "input.gltf");
    fuzz::write_file(file, data, size);
    const std::string scene_path = (fuzz::scratch_dir() / "input-scene.json").string();
    auto rig = gltf::make_rig_scene(file.string(), scene_path, gltf::RigOptions{});
    if (!rig) {
        if (rig.error().message.find(file.string()) == std::string::npos) {
            fuzz::finding("the error does not name the file: " + rig.error().message);
        }
        return 0;
    }
    auto scene = parse_scene(rig.value().json, scene_path);
    if (!scene) fuzz::finding("the rig's scene does not load: " + scene.error().message);
    auto rods = build_rod_scene(scene.value());
    if (!rods) fuzz::finding("the rig's scene does not build: " + rods.error().message);
    return 0;
}
