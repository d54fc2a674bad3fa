// Chain setup from rigged glTF characters (SPEC A.7, issue 4): named roots and name
// patterns on the shipped sample files, with expected values computed from the files'
// own numbers, and hand-built characters for the branch, 32-joint and error rules.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "kodawari/gltf/chains.hpp"
#include "kodawari/gltf/import.hpp"
#include "kodawari/rods/solver.hpp"
#include "test_paths.hpp"

namespace kodawari {
namespace {

using nlohmann::json;

const std::string kAssets = std::string(KODAWARI_SOURCE_DIR) + "/tests/assets";
const std::string kRiggedSimple = kAssets + "/khronos/RiggedSimple.gltf";
const std::array<std::string, 3> kSpringFiles = {"inside-collider.gltf", "plane-collider.gltf", "sphere-collider.gltf"};

animation::Character load(const std::string& path) {
    auto character = gltf::load_character(path);
    EXPECT_TRUE(character.ok()) << (character.ok() ? "" : character.error().message);
    return std::move(character).value();
}

json read_json(const std::string& path) {
    std::ifstream in(path);
    return json::parse(in);
}

// A column-major 4x4 in double, as glTF stores `matrix`.
using Mat = std::array<double, 16>;

Mat multiply(const Mat& a, const Mat& b) {
    Mat c{};
    for (int col = 0; col < 4; ++col)
        for (int row = 0; row < 4; ++row)
            for (int k = 0; k < 4; ++k) c[col * 4 + row] += a[k * 4 + row] * b[col * 4 + k];
    return c;
}

// A node's local matrix from the JSON, in double: `matrix`, or T * R * S (§3.5.3).
Mat local_matrix(const json& node) {
    Mat m{};
    if (node.contains("matrix")) {
        for (int i = 0; i < 16; ++i) m[static_cast<std::size_t>(i)] = node["matrix"][static_cast<std::size_t>(i)].get<double>();
        return m;
    }
    std::array<double, 3> t{0, 0, 0}, s{1, 1, 1};
    std::array<double, 4> q{0, 0, 0, 1};
    if (node.contains("translation")) for (std::size_t i = 0; i < 3; ++i) t[i] = node["translation"][i].get<double>();
    if (node.contains("scale")) for (std::size_t i = 0; i < 3; ++i) s[i] = node["scale"][i].get<double>();
    if (node.contains("rotation")) for (std::size_t i = 0; i < 4; ++i) q[i] = node["rotation"][i].get<double>();
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const std::array<double, 9> r = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
                                     2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                                     2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)};
    for (int col = 0; col < 3; ++col)
        for (int row = 0; row < 3; ++row) m[static_cast<std::size_t>(col * 4 + row)] = r[static_cast<std::size_t>(col * 3 + row)] * s[static_cast<std::size_t>(col)];
    m[12] = t[0];
    m[13] = t[1];
    m[14] = t[2];
    m[15] = 1;
    return m;
}

// World matrices of every node of a glTF JSON, in double, independently of the engine.
std::vector<Mat> world_matrices(const json& doc) {
    const std::size_t n = doc["nodes"].size();
    std::vector<int> parent(n, -1);
    for (std::size_t i = 0; i < n; ++i)
        if (doc["nodes"][i].contains("children"))
            for (const auto& c : doc["nodes"][i]["children"]) parent[c.get<std::size_t>()] = static_cast<int>(i);
    std::vector<Mat> world(n);
    std::vector<bool> done(n, false);
    for (std::size_t pass = 0; pass < n; ++pass)
        for (std::size_t i = 0; i < n; ++i) {
            if (done[i]) continue;
            if (parent[i] < 0) {
                world[i] = local_matrix(doc["nodes"][i]);
                done[i] = true;
            } else if (done[static_cast<std::size_t>(parent[i])]) {
                world[i] = multiply(world[static_cast<std::size_t>(parent[i])], local_matrix(doc["nodes"][i]));
                done[i] = true;
            }
        }
    return world;
}

double distance(const Mat& a, const Mat& b) {
    return std::sqrt((a[12] - b[12]) * (a[12] - b[12]) + (a[13] - b[13]) * (a[13] - b[13]) + (a[14] - b[14]) * (a[14] - b[14]));
}

// A hand-built character: nodes added with a parent and a local translation; finish()
// fills the children, roots and parents-first order the loader would.
struct Builder {
    animation::Character character;
    int add(const std::string& name, int parent, glm::vec3 translation) {
        animation::Node node;
        node.name = name;
        node.parent = parent;
        node.translation = translation;
        character.nodes.push_back(node);
        const int index = static_cast<int>(character.nodes.size()) - 1;
        if (parent >= 0) character.nodes[static_cast<std::size_t>(parent)].children.push_back(index);
        else character.roots.push_back(index);
        return index;
    }
    // A strand of `count` nodes named prefix00.., each `step` below the previous one.
    int strand(const std::string& prefix, int parent, int count, glm::vec3 step) {
        int first = -1;
        for (int i = 0; i < count; ++i) {
            const std::string number = (i < 10 ? "0" : "") + std::to_string(i);
            parent = add(prefix + number, parent, step);
            if (first < 0) first = parent;
        }
        return first;
    }
    animation::Character finish() {
        character.source = "hand-built.gltf";
        // Nodes are added after their parents, so index order is parents first.
        for (std::size_t i = 0; i < character.nodes.size(); ++i) character.order.push_back(static_cast<int>(i));
        return character;
    }
};

// Every found chain must be accepted by the solver with the scaled parameters.
void expect_simulable(const animation::Character& character, const gltf::ChainSetup& setup) {
    for (const auto& chain : setup.chains) {
        const gltf::PhysicsScale physics = gltf::scaled_physics(character, chain);
        EXPECT_GT(physics.thickness, 0.0f) << chain.name;
        EXPECT_GT(physics.mass, 0.0f) << chain.name;
        const auto made = rods::make_chain(chain.base, physics.thickness, physics.mass);
        EXPECT_TRUE(made.ok()) << chain.name << ": " << (made.ok() ? "" : made.error().message);
    }
}

TEST(GltfChains, RiggedSimpleNamedRootMatchesBindPose) {
    const animation::Character character = load(kRiggedSimple);
    gltf::ChainSearch search;
    search.roots = {"Bone"};
    const auto setup = gltf::find_chains(character, search);
    ASSERT_TRUE(setup.ok()) << setup.error().message;
    ASSERT_EQ(setup.value().chains.size(), 1u);
    EXPECT_TRUE(setup.value().warnings.empty());
    const gltf::FoundChain& chain = setup.value().chains[0];
    EXPECT_EQ(chain.name, "Bone");
    EXPECT_EQ(chain.nodes, (std::vector<int>{3, 4}));  // Bone -> Bone.001, a leaf
    EXPECT_EQ(chain.parent, 1);                        // Armature
    ASSERT_EQ(chain.base.positions.size(), 2u);

    // Expected from the file's numbers in double: the distance of the two bones' world
    // origins through Z_UP * Armature * Bone (matrices) and Bone.001's TRS. Tolerance
    // 1e-5 m: the engine works in float, about 4.8e-7 m per rounding at this 4.19 m
    // length, over a handful of matrix products.
    const json doc = read_json(kRiggedSimple);
    const std::vector<Mat> world = world_matrices(doc);
    const double expected_length = distance(world[3], world[4]);
    EXPECT_NEAR(expected_length, 4.18717, 1e-5);  // sanity of the reference itself
    EXPECT_NEAR(chain.length, expected_length, 1e-5);
    EXPECT_NEAR(glm::length(chain.base.positions[1]), expected_length, 1e-5);
    // Bone's world transform is rigid (rotations and a translation only), so in its frame
    // Bone.001 sits at its own local translation and has its own local rotation.
    EXPECT_EQ(chain.base.positions[0], glm::vec3(0.0f));
    for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_NEAR(chain.base.positions[1][static_cast<glm::length_t>(i)], doc["nodes"][4]["translation"][i].get<double>(), 1e-5) << i;
    }
    const glm::quat expected_rotation(doc["nodes"][4]["rotation"][3].get<float>(), doc["nodes"][4]["rotation"][0].get<float>(),
                                      doc["nodes"][4]["rotation"][1].get<float>(), doc["nodes"][4]["rotation"][2].get<float>());
    EXPECT_NEAR(std::abs(glm::dot(chain.base.orientations[1], expected_rotation)), 1.0, 1e-6);
    expect_simulable(character, setup.value());
}

TEST(GltfChains, RiggedSimpleHasNoChainByDefaultPatterns) {
    // Z_UP, Armature, Cylinder, Bone, Bone.001: none names hair, ears or the like.
    const auto setup = gltf::find_chains(load(kRiggedSimple), gltf::ChainSearch{});
    ASSERT_TRUE(setup.ok()) << setup.error().message;
    EXPECT_TRUE(setup.value().chains.empty());
    EXPECT_TRUE(setup.value().warnings.empty());
}

TEST(GltfChains, SpringBoneSamplesByDefaultPatterns) {
    // Each file: "Spring A" at (0, 2, 0) scaled by 0.25, then B..E each (0, -2, 0) below
    // its parent in the parent's (scaled) frame, so 0.5 m apart in the world; "Collider"
    // is a separate scene root and does not match.
    for (const std::string& file : kSpringFiles) {
        SCOPED_TRACE(file);
        const animation::Character character = load(kAssets + "/vrm-springbone/" + file);
        const auto setup = gltf::find_chains(character, gltf::ChainSearch{});
        ASSERT_TRUE(setup.ok()) << setup.error().message;
        EXPECT_TRUE(setup.value().warnings.empty());
        ASSERT_EQ(setup.value().chains.size(), 1u);
        const gltf::FoundChain& chain = setup.value().chains[0];
        EXPECT_EQ(chain.name, "Spring A");
        EXPECT_EQ(chain.nodes, (std::vector<int>{0, 1, 2, 3, 4}));
        EXPECT_EQ(chain.parent, -1);
        EXPECT_NEAR(chain.length, 2.0f, 1e-6f);
        for (std::size_t i = 0; i < 5; ++i) {
            // The root's scale is removed from the frame: positions are world metres.
            EXPECT_NEAR(chain.base.positions[i].y, -0.5f * static_cast<float>(i), 1e-6f) << i;
            EXPECT_NEAR(std::abs(chain.base.orientations[i].w), 1.0f, 1e-6f) << i;
        }
        expect_simulable(character, setup.value());
    }
}

TEST(GltfChains, WildcardPatternsMatchWholeNamesAndWordsMatchWithin) {
    // Issue 37: `rig --chains 'tail*'` found nothing, as patterns were substrings only.
    // "Spring A" is the samples' chain root; "Collider" a separate root that never matches.
    const animation::Character character = load(kAssets + "/vrm-springbone/" + kSpringFiles.front());
    const auto found = [&](std::vector<std::string> patterns) {
        gltf::ChainSearch search;
        search.patterns = std::move(patterns);
        const auto setup = gltf::find_chains(character, search);
        EXPECT_TRUE(setup.ok()) << setup.error().message;
        return setup.ok() ? setup.value().chains.size() : std::size_t{99};
    };
    EXPECT_EQ(found({"spring*"}), 1u);      // the whole name, case-insensitive
    EXPECT_EQ(found({"SPRING ?"}), 1u);     // '?' is one character
    EXPECT_EQ(found({"*a"}), 1u);           // anchored at the end
    EXPECT_EQ(found({"pring*"}), 0u);       // a wildcard pattern is anchored at the start
    EXPECT_EQ(found({"spring"}), 1u);       // a word is a substring, as before
    EXPECT_EQ(found({"pring"}), 1u);
    EXPECT_EQ(found({"spring ??"}), 0u);    // one character too many
}

TEST(GltfChains, SpringBonePhysicsScaleWithSize) {
    // inside-collider: nodes at y = 2, 1.5, 1, 0.5, 0 and the collider at (0, 1, 0):
    // size 2 m, thickness 0.006 * 2 = 1.2 cm, mass 300 * pi * 0.012^2 * 0.5 = 67.9 g.
    const animation::Character character = load(kAssets + "/vrm-springbone/inside-collider.gltf");
    EXPECT_NEAR(gltf::character_size(character), 2.0f, 1e-6f);
    const auto setup = gltf::find_chains(character, gltf::ChainSearch{});
    ASSERT_TRUE(setup.ok() && setup.value().chains.size() == 1);
    const gltf::PhysicsScale physics = gltf::scaled_physics(character, setup.value().chains[0]);
    EXPECT_NEAR(physics.thickness, 0.012f, 1e-7f);
    EXPECT_NEAR(physics.mass, 300.0 * 3.14159265358979 * 0.012 * 0.012 * 0.5, 1e-6);
    // sphere-collider: the collider at (0.75, 1, 0) widens the box to 0.75 x 2.
    EXPECT_NEAR(gltf::character_size(load(kAssets + "/vrm-springbone/sphere-collider.gltf")),
                std::sqrt(0.75f * 0.75f + 4.0f), 1e-6f);
}

TEST(GltfChains, NamedRootInsideStrandAndOverlap) {
    const animation::Character character = load(kAssets + "/vrm-springbone/inside-collider.gltf");
    gltf::ChainSearch search;
    search.roots = {"Spring C"};
    const auto setup = gltf::find_chains(character, search);
    ASSERT_TRUE(setup.ok()) << setup.error().message;
    ASSERT_EQ(setup.value().chains.size(), 1u);
    EXPECT_EQ(setup.value().chains[0].nodes, (std::vector<int>{2, 3, 4}));
    EXPECT_EQ(setup.value().chains[0].parent, 1);  // hangs from Spring B, kinematic here

    search.roots = {"Spring A", "Spring C"};
    const auto overlap = gltf::find_chains(character, search);
    ASSERT_FALSE(overlap.ok());
    EXPECT_EQ(overlap.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(overlap.error().message.find("Spring C"), std::string::npos) << overlap.error().message;
}

TEST(GltfChains, MissingRootNamesFileAndNode) {
    gltf::ChainSearch search;
    search.roots = {"Bone", "NoSuchBone"};
    const auto setup = gltf::find_chains(load(kRiggedSimple), search);
    ASSERT_FALSE(setup.ok());
    EXPECT_EQ(setup.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(setup.error().message.find("RiggedSimple.gltf"), std::string::npos) << setup.error().message;
    EXPECT_NE(setup.error().message.find("\"NoSuchBone\""), std::string::npos) << setup.error().message;
}

TEST(GltfChains, MinJointsSkipsWithWarning) {
    const animation::Character character = load(kAssets + "/vrm-springbone/plane-collider.gltf");
    gltf::ChainSearch search;
    search.min_joints = 6;  // the strand has 5
    const auto setup = gltf::find_chains(character, search);
    ASSERT_TRUE(setup.ok()) << setup.error().message;
    EXPECT_TRUE(setup.value().chains.empty());
    ASSERT_EQ(setup.value().warnings.size(), 1u);
    EXPECT_NE(setup.value().warnings[0].find("Spring A"), std::string::npos) << setup.value().warnings[0];
    EXPECT_NE(setup.value().warnings[0].find("plane-collider.gltf"), std::string::npos) << setup.value().warnings[0];
}

// Head with: a hair strand that branches after two joints into two strands, a 40-joint
// tail, a forearm and hand ("ear" in "ForeArm" must not match), and a leaf ear.
animation::Character branching_character() {
    Builder b;
    const int head = b.add("Head", -1, {0.0f, 1.6f, 0.0f});
    const int hair = b.add("Hair_Root", head, {0.0f, 0.1f, 0.0f});
    const int mid = b.add("Hair_Mid", hair, {0.0f, -0.05f, 0.0f});
    b.strand("hair_L", mid, 3, {-0.02f, -0.04f, 0.0f});
    b.strand("hair_R", mid, 2, {0.02f, -0.04f, 0.0f});
    b.strand("Tail", head, 40, {0.0f, 0.0f, -0.02f});
    const int forearm = b.add("mixamorig:LeftForeArm", head, {0.3f, -0.3f, 0.0f});
    b.add("mixamorig:LeftHand", forearm, {0.25f, 0.0f, 0.0f});
    b.add("Ear_L", head, {-0.08f, 0.0f, 0.0f});
    return b.finish();
}

TEST(GltfChains, BranchEndsChainAndLongStrandIsTruncated) {
    const animation::Character character = branching_character();
    const auto setup = gltf::find_chains(character, gltf::ChainSearch{});
    ASSERT_TRUE(setup.ok()) << setup.error().message;
    const auto& chains = setup.value().chains;
    ASSERT_EQ(chains.size(), 4u);
    // The hair root chain ends at the branching node; each branch is its own chain
    // hanging from it.
    EXPECT_EQ(chains[0].name, "Hair_Root");
    EXPECT_EQ(chains[0].nodes, (std::vector<int>{1, 2}));
    EXPECT_EQ(chains[0].parent, 0);
    EXPECT_EQ(chains[1].name, "hair_L00");
    EXPECT_EQ(chains[1].nodes, (std::vector<int>{3, 4, 5}));
    EXPECT_EQ(chains[1].parent, 2);
    EXPECT_EQ(chains[2].name, "hair_R00");
    EXPECT_EQ(chains[2].nodes, (std::vector<int>{6, 7}));
    EXPECT_EQ(chains[2].parent, 2);
    // The tail keeps 32 of its 40 joints; Tail32..Tail39 start no chain of their own.
    EXPECT_EQ(chains[3].name, "Tail00");
    ASSERT_EQ(chains[3].nodes.size(), 32u);
    EXPECT_EQ(chains[3].nodes.front(), 8);
    EXPECT_EQ(chains[3].nodes.back(), 39);
    EXPECT_NEAR(chains[3].length, 31 * 0.02f, 1e-5f);
    EXPECT_NEAR(chains[3].base.positions[31].z, -31 * 0.02f, 1e-5f);
    // Warnings: the truncated tail (naming the first node left out) and the leaf ear.
    ASSERT_EQ(setup.value().warnings.size(), 2u);
    EXPECT_NE(setup.value().warnings[0].find("\"Tail32\""), std::string::npos) << setup.value().warnings[0];
    EXPECT_NE(setup.value().warnings[1].find("Ear_L"), std::string::npos) << setup.value().warnings[1];
    expect_simulable(character, setup.value());

    // The same tail by name: the same 32 joints and warning.
    gltf::ChainSearch search;
    search.roots = {"Tail00"};
    const auto named = gltf::find_chains(character, search);
    ASSERT_TRUE(named.ok()) << named.error().message;
    ASSERT_EQ(named.value().chains.size(), 1u);
    EXPECT_EQ(named.value().chains[0].nodes, chains[3].nodes);
    EXPECT_EQ(named.value().warnings.size(), 1u);
}

TEST(GltfChains, OrientationsAreInRootFrame) {
    // A root turned a quarter turn about +Z and placed away from the origin: in its own
    // frame the strand still lies along the children's local translations, whatever the
    // root's world transform.
    Builder b;
    const int root = b.add("ribbon", -1, {1.0f, 2.0f, 3.0f});
    b.character.nodes[static_cast<std::size_t>(root)].rotation = glm::angleAxis(1.5707963f, glm::vec3(0, 0, 1));
    const int second = b.add("ribbon_1", root, {0.0f, -0.1f, 0.0f});
    b.character.nodes[static_cast<std::size_t>(second)].rotation = glm::angleAxis(0.5f, glm::vec3(1, 0, 0));
    b.add("ribbon_2", second, {0.0f, -0.1f, 0.0f});
    const animation::Character character = b.finish();
    const auto setup = gltf::find_chains(character, gltf::ChainSearch{});
    ASSERT_TRUE(setup.ok()) << setup.error().message;
    ASSERT_EQ(setup.value().chains.size(), 1u);
    const rods::ChainShape& base = setup.value().chains[0].base;
    EXPECT_NEAR(base.positions[1].x, 0.0f, 1e-6f);
    EXPECT_NEAR(base.positions[1].y, -0.1f, 1e-6f);
    // Joint 2 is 0.1 m along joint 1's -Y, which is turned 0.5 rad about X.
    EXPECT_NEAR(base.positions[2].y, -0.1f - 0.1f * std::cos(0.5f), 1e-6f);
    EXPECT_NEAR(base.positions[2].z, -0.1f * std::sin(0.5f), 1e-6f);
    EXPECT_NEAR(std::abs(glm::dot(base.orientations[1], glm::angleAxis(0.5f, glm::vec3(1, 0, 0)))), 1.0f, 1e-6f);
    expect_simulable(character, setup.value());
}

TEST(GltfChains, ZeroLengthSegmentNamesNode) {
    Builder b;
    const int root = b.add("hair", -1, {0.0f, 0.0f, 0.0f});
    const int tip = b.add("hair_tip", root, {0.0f, -0.1f, 0.0f});
    b.add("hair_tip_end", tip, {0.0f, 0.0f, 0.0f});  // an end bone at its parent's place
    const auto setup = gltf::find_chains(b.finish(), gltf::ChainSearch{});
    ASSERT_FALSE(setup.ok());
    EXPECT_EQ(setup.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(setup.error().message.find("\"hair_tip_end\""), std::string::npos) << setup.error().message;
    EXPECT_NE(setup.error().message.find("hand-built.gltf"), std::string::npos) << setup.error().message;
}

}  // namespace
}  // namespace kodawari
