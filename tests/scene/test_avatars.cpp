// The VRoid-class test avatars of issue 18 (scenes/characters/avatar.vrm, a VRM 1.0
// avatar, and avatar-vrm0.vrm, the same as VRM 0.x, both written by make_avatar.py) rigged
// by `kodawari rig` with the generated VRM Animation walk (scenes/motions/walk.vrma, keyed
// on a taller skeleton of its own): each spring keeps its own collider groups and center,
// the hair stays outside the head's colliders and swings with the walk, and the export
// is valid glTF. The crowd of 200 on every backend is in
// tests/backends/test_character_backends.cpp.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "character_support.hpp"
#include "test_support.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/export/export.hpp"
#include "kodawari/gltf/rig_scene.hpp"
#include "test_paths.hpp"

namespace kodawari {
namespace {

using nlohmann::json;
using testing_support::TempDir;
using testing_support::characters::Simulation;

const std::string kSource = KODAWARI_SOURCE_DIR;
const std::string kAvatar = kSource + "/scenes/characters/avatar.vrm";
const std::string kAvatar0 = kSource + "/scenes/characters/avatar-vrm0.vrm";
const std::string kWalk = kSource + "/scenes/motions/walk.vrma";

// The JSON chunk of a GLB file, read here independently of the engine's loader.
json glb_json(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_GE(bytes.size(), 20u);
    std::uint32_t length = 0;
    std::memcpy(&length, bytes.data() + 12, 4);
    return json::parse(std::string(bytes.data() + 20, length));
}

// `kodawari rig AVATAR --motion walk.vrma`'s scene, written into `dir`.
std::string rig(const std::string& avatar, const TempDir& dir, const std::string& name, bool animate = true) {
    gltf::RigOptions options;
    options.motions = {kWalk};
    options.duration = 3.0f;
    const std::string out = dir.file(name);
    auto rigged = gltf::make_rig_scene(avatar, out, options);
    EXPECT_TRUE(rigged.ok()) << (rigged.ok() ? "" : rigged.error().message);
    std::string text = rigged.ok() ? rigged.value().json : std::string();
    if (!animate) {
        json scene = json::parse(text);
        scene["characters"][0].erase("animation");
        scene["characters"][0]["animate"] = false;
        text = scene.dump();
    }
    std::ofstream(out) << text;
    return out;
}

// Each spring of the VRM 1.0 avatar becomes a chain that lists exactly the colliders of
// its own collider groups (read here from the file), and the spring with a `center`
// measures its inertia in that node. The VRM 0.x avatar's bone groups likewise, from the
// flattened collider groups of each group. The scenes load, with each chain instance
// taking as many colliders as its list.
TEST(Avatars, RigKeepsEachSpringsColliderGroupsAndCenter) {
    TempDir dir;
    {
        const json file = glb_json(kAvatar);
        const json& springs = file["extensions"]["VRMC_springBone"];
        const json scene = json::parse(std::ifstream(rig(kAvatar, dir, "vrm1.json")));
        const json& chains = scene["characters"][0]["chains"];
        ASSERT_EQ(chains.size(), springs["springs"].size());
        ASSERT_EQ(scene["characters"][0]["colliders"].size(), springs["colliders"].size());
        EXPECT_EQ(scene["characters"][0]["motions"][0]["name"], "walk");
        int centers = 0;
        for (std::size_t s = 0; s < chains.size(); ++s) {
            const json& spring = springs["springs"][s];
            std::set<std::string> want;
            for (const json& g : spring["colliderGroups"]) {
                for (const json& c : springs["colliderGroups"][g.get<std::size_t>()]["colliders"]) {
                    want.insert("collider" + std::to_string(c.get<int>()));
                }
            }
            std::set<std::string> got;
            for (const json& c : chains[s].value("colliders", json::array())) got.insert(c.get<std::string>());
            EXPECT_EQ(got, want) << chains[s]["name"];
            if (spring.contains("center")) {
                ++centers;
                EXPECT_EQ(chains[s]["center"], file["nodes"][spring["center"].get<std::size_t>()]["name"]);
            } else {
                EXPECT_FALSE(chains[s].contains("center")) << chains[s]["name"];
            }
        }
        EXPECT_EQ(centers, 1);
        const RodScene rods = testing_support::characters::build(testing_support::characters::load_file(dir.file("vrm1.json")));
        ASSERT_EQ(rods.world.chains.size(), chains.size());
        for (std::size_t c = 0; c < chains.size(); ++c) {
            EXPECT_EQ(rods.world.chains[c].collider_count, chains[c]["colliders"].size()) << chains[c]["name"];
        }
        EXPECT_EQ(rods.world.center_count, 1u);
    }
    {
        const json file = glb_json(kAvatar0);
        const json& secondary = file["extensions"]["VRM"]["secondaryAnimation"];
        std::vector<std::vector<int>> flattened;  // per collider group, its colliders' indices
        int next = 0;
        for (const json& g : secondary["colliderGroups"]) {
            flattened.emplace_back();
            for (std::size_t k = 0; k < g["colliders"].size(); ++k) flattened.back().push_back(next++);
        }
        const json scene = json::parse(std::ifstream(rig(kAvatar0, dir, "vrm0.json")));
        const json& chains = scene["characters"][0]["chains"];
        EXPECT_EQ(scene["characters"][0]["colliders"].size(), static_cast<std::size_t>(next));
        std::size_t checked = 0;
        int centers = 0;
        for (const json& chain : chains) {
            const std::string root = chain["root"].get<std::string>();
            for (const json& group : secondary["boneGroups"]) {
                bool mine = false;
                for (const json& b : group["bones"]) mine = mine || file["nodes"][b.get<std::size_t>()]["name"] == root;
                if (!mine) continue;
                std::set<std::string> want;
                for (const json& g : group["colliderGroups"]) {
                    for (const int c : flattened[g.get<std::size_t>()]) want.insert("collider" + std::to_string(c));
                }
                std::set<std::string> got;
                for (const json& c : chain.value("colliders", json::array())) got.insert(c.get<std::string>());
                if (want.size() <= 16) {
                    EXPECT_EQ(got, want) << root;
                } else {  // one chain touches at most 16: the first 16 of the group's, with a warning
                    EXPECT_EQ(got.size(), 16u) << root;
                    EXPECT_TRUE(std::includes(want.begin(), want.end(), got.begin(), got.end())) << root;
                }
                const int center = group.value("center", -1);
                if (center >= 0) {
                    ++centers;
                    EXPECT_EQ(chain["center"], file["nodes"][static_cast<std::size_t>(center)]["name"]) << root;
                }
                ++checked;
            }
        }
        EXPECT_EQ(checked, chains.size()) << "every chain starts at a bone group's root";
        EXPECT_GE(centers, 1);
        const RodScene rods = testing_support::characters::build(testing_support::characters::load_file(dir.file("vrm0.json")));
        EXPECT_EQ(rods.world.chains.size(), chains.size());
    }
}

// The hair of the VRM 1.0 avatar walking for 3 s (the CPU reference): every hair joint
// stays outside every head collider of the file (its spheres read from the JSON here and
// placed by the head node's pose), and the strands swing with the walk: the tips move in
// the head's frame several times more than on the avatar standing in its rest pose.
// Bounds: the head's six spheres overlap, and the solver projects collider by collider,
// so pushing a particle out of one can leave it slightly inside another already done;
// 1 mm (1/20 of the smallest head sphere's radius) is what a strand may rest inside the
// union, and the run prints the deepest. The swing: the walk keeps the head level and
// facing forward but bobs and sways it by 2 to 3 cm each stride, which the 15 to 25 cm
// strands answer with tips moving about 2 mm (RMS) in the head's frame (measured 1.8 mm);
// standing, they settle and move by less than a micrometre. Bounds: 1 mm, and 100 times
// the standing tips' motion.
TEST(Avatars, HairStaysOutsideTheHeadAndSwingsWithTheWalk) {
    TempDir dir;
    const json file = glb_json(kAvatar);
    const int head = file["extensions"]["VRMC_vrm"]["humanoid"]["humanBones"]["head"]["node"].get<int>();
    struct Sphere {
        glm::vec3 offset;
        float radius;
    };
    std::vector<Sphere> spheres;
    for (const json& c : file["extensions"]["VRMC_springBone"]["colliders"]) {
        if (c["node"].get<int>() != head || !c["shape"].contains("sphere")) continue;
        const json& s = c["shape"]["sphere"];
        spheres.push_back({{s["offset"][0].get<float>(), s["offset"][1].get<float>(), s["offset"][2].get<float>()}, s["radius"].get<float>()});
    }
    ASSERT_GE(spheres.size(), 4u);

    float tip_motion[2] = {0.0f, 0.0f};  // walking, standing: mean over hair strands of the tip's RMS motion in the head's frame
    float deepest = 0.0f;
    for (const bool walking : {true, false}) {
        SCOPED_TRACE(walking ? "walking" : "standing");
        const RodScene rs = testing_support::characters::build(
            testing_support::characters::load_file(rig(kAvatar, dir, walking ? "walk.json" : "still.json", walking)));
        Simulation sim(rs);
        std::vector<std::uint32_t> hair;
        for (std::uint32_t c = 0; c < rs.world.chains.size(); ++c) {
            if (rs.chain_names[c].find("J_Sec_Hair") != std::string::npos) hair.push_back(c);
        }
        ASSERT_GE(hair.size(), 20u);
        std::vector<std::vector<glm::vec3>> tips(hair.size());
        for (std::uint32_t f = 1; f < 180; ++f) {
            sim.step(f);
            const std::vector<rods::Transform> nodes = rs.joint_poses(0, f);
            const rods::Transform& h = nodes[static_cast<std::size_t>(head)];
            for (std::size_t k = 0; k < hair.size(); ++k) {
                const rods::Chain& chain = rs.world.templ(rs.world.chains[hair[k]]).chain;
                for (std::uint32_t i = 1; i < chain.joint_count; ++i) {
                    for (const Sphere& s : spheres) {
                        const float gap = glm::length(sim.x(hair[k], i) - (h.position + h.rotation * s.offset)) - s.radius - chain.thickness;
                        deepest = std::max(deepest, -gap);
                    }
                }
                if (f >= 60) tips[k].push_back(glm::conjugate(h.rotation) * (sim.x(hair[k], chain.joint_count - 1) - h.position));
            }
        }
        float sum = 0.0f;
        for (const std::vector<glm::vec3>& t : tips) {
            glm::vec3 mean(0.0f);
            for (const glm::vec3& p : t) mean += p / static_cast<float>(t.size());
            float var = 0.0f;
            for (const glm::vec3& p : t) var += glm::dot(p - mean, p - mean) / static_cast<float>(t.size());
            sum += std::sqrt(var);
        }
        tip_motion[walking ? 0 : 1] = sum / static_cast<float>(tips.size());
    }
    std::printf("[ measured ] hair inside the head's spheres by at most %.3g m; tip motion in the head's frame: walking %.3g m, "
                "standing %.3g m (RMS, mean over strands)\n",
                static_cast<double>(deepest), static_cast<double>(tip_motion[0]), static_cast<double>(tip_motion[1]));
    EXPECT_LT(deepest, 1e-3f);
    EXPECT_GT(tip_motion[0], 100.0f * tip_motion[1]);
    EXPECT_GT(tip_motion[0], 1e-3f);
}

// Three walking avatars simulated for 30 frames and exported into the avatar's own file
// (RiggedCrowdExport): glTF-Validator finds no error (the VRM extensions it does not know
// are infos), and Blender's own importer, where installed, makes one armature and one
// action per avatar (tests/tools/blender_check.py).
TEST(Avatars, CrowdExportIsValidGltf) {
    TempDir dir;
    Scene scene = testing_support::characters::load_file(rig(kAvatar, dir, "walk.json"));
    scene.crowds.clear();
    CrowdSpec crowd;
    crowd.character = 0;
    crowd.count = 3;
    crowd.time_offset = 1.0f;
    scene.crowds.push_back(crowd);
    const RodScene rs = testing_support::characters::build(scene);
    auto backend = make_rod_backend(BackendKind::Cpu, BackendOptions{});
    ASSERT_TRUE(backend.ok());
    auto exporter = RiggedCrowdExport::create(rs, 0, {}, {});
    ASSERT_TRUE(exporter.ok()) << exporter.error().message;
    ChainSnapshot snap;
    for (std::uint32_t f = 0; f < 30; ++f) {
        const rods::RodFrame input = rs.frame(f);
        ASSERT_TRUE((f == 0 ? backend.value()->load(rs.world, input) : backend.value()->step(input)).ok());
        ASSERT_TRUE(backend.value()->read(snap).ok());
        ASSERT_TRUE(exporter.value().add_frame(f, snap).ok());
    }
    const std::string path = dir.file("avatars.glb");
    ASSERT_TRUE(exporter.value().finish(path).ok());
    std::string output;
    ASSERT_EQ(testing_support::run_command(testing_support::gltf_validator_command(path), output), 0) << output;
    EXPECT_NE(output.find("glTF-Validator: 0 errors"), std::string::npos) << output;
    std::printf("%s\n", output.substr(0, 300).c_str());
    if (testing_support::run_command("command -v blender", output) != 0) {
        std::printf("SKIPPED the Blender import: blender not installed (bash scripts/setup --with-blender installs it)\n");
        return;
    }
    const std::string line = testing_support::blender_report_line(path, output);
    ASSERT_FALSE(line.empty()) << output;
    const json report = json::parse(line);
    EXPECT_EQ(report.at("armature_count").get<std::size_t>(), 3u) << line;
    EXPECT_EQ(report.at("actions").get<std::size_t>(), 3u) << line;
}

}  // namespace
}  // namespace kodawari
