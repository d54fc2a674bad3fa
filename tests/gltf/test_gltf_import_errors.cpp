// glTF 2.0 character import, bad input (issue 4): one test per kind, each error naming
// the file, the glTF path and what was expected.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "gltf_import_support.hpp"

namespace kodawari {
namespace {

using namespace gltf_import_test;  // its helpers, TempDir, json and fs

// --- bad input -------------------------------------------------------------------------

TEST(GltfImportErrors, AMissingFileIsBadInput) {
    // Issue 37: a missing input file is bad input (exit 2), as a malformed one is.
    TempDir dir;
    const auto loaded = gltf::load_character(dir.file("absent.gltf"));
    ASSERT_FALSE(loaded.ok());
    EXPECT_EQ(loaded.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(loaded.error().message.find("absent.gltf"), std::string::npos) << loaded.error().message;
}

TEST(GltfImportErrors, TruncatedGltf) {
    TempDir dir;
    const std::vector<unsigned char> whole = read_all(kRiggedSimple);
    const std::string file = dir.file("RiggedSimple.gltf");
    write_bytes(file, std::vector<unsigned char>(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(whole.size() / 2)));
    expect_error(file, "$", "invalid JSON");
    // Every cut must fail cleanly (none is a complete document); steps of 97 bytes keep
    // the test fast while hitting every part of the file.
    for (std::size_t n = 0; n < whole.size(); n += 97) {
        write_bytes(file, std::vector<unsigned char>(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(n)));
        const auto loaded = gltf::load_character(file);
        ASSERT_FALSE(loaded.ok()) << n;
        EXPECT_EQ(loaded.error().message.rfind(file + ": ", 0), 0u) << loaded.error().message;
    }
}

// A file named as the model that is not glTF at all (a README, an image, the model's
// .bin, an empty file) is said to be so, with its first bytes, rather than as the JSON
// parser's complaint about its first byte.
TEST(GltfImportErrors, AFileThatIsNotGltfSaysSo) {
    TempDir dir;
    const std::string file = dir.file("model.gltf");
    const std::string text = "# My model\nSee model.glb.\n";
    write_bytes(file, std::vector<unsigned char>(text.begin(), text.end()));
    expect_error(file, "$", "not a glTF file: it starts with \"# My mod\", where a .gltf starts with a JSON object ('{') and a .glb "
                            "with \"glTF\"");
    write_bytes(file, {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0});
    expect_error(file, "$", "not a glTF file: it starts with \"\\x89PNG\\x0d\\x0a\\x1a\\x0a\"");
    write_bytes(file, {});
    expect_error(file, "$", "not a glTF file: it is empty (or whitespace alone)");
    // A byte order mark and whitespace before the object are JSON's; the object is read.
    const std::vector<unsigned char> whole = read_all(kRiggedSimple);
    std::vector<unsigned char> marked = {0xEF, 0xBB, 0xBF, ' ', '\n'};
    marked.insert(marked.end(), whole.begin(), whole.end());
    const std::string rigged = dir.file("RiggedSimple.gltf");
    write_bytes(rigged, marked);
    const auto loaded = gltf::load_character(rigged);
    EXPECT_TRUE(loaded.ok()) << loaded.error().message;
}

TEST(GltfImportErrors, TruncatedGlb) {
    TempDir dir;
    const std::vector<unsigned char> whole = tiny_character().glb();
    const std::string file = dir.file("tiny.glb");
    write_bytes(file, std::vector<unsigned char>(whole.begin(), whole.end() - 10));
    expect_error(file, "GLB header", "truncated");
    write_bytes(file, std::vector<unsigned char>(whole.begin(), whole.begin() + 7));
    expect_error(file, "GLB header", "fewer than the 12-byte header");
    // Cuts every 7 bytes (7 is coprime with the 4-byte alignment of headers and chunks,
    // so every offset within a word is hit), each one a clean error.
    for (std::size_t n = 0; n < whole.size(); n += 7) {
        write_bytes(file, std::vector<unsigned char>(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(n)));
        const auto loaded = gltf::load_character(file);
        ASSERT_FALSE(loaded.ok()) << n;
        EXPECT_EQ(loaded.error().kind, Error::Kind::InvalidInput) << n;
        EXPECT_EQ(loaded.error().message.rfind(file + ": GLB ", 0), 0u) << loaded.error().message;
    }
}

TEST(GltfImportErrors, WrongMagic) {
    TempDir dir;
    std::vector<unsigned char> bytes = tiny_character().glb();
    bytes[1] = 'L';  // "gLTF"
    const std::string file = dir.file("tiny.glb");
    write_bytes(file, bytes);
    expect_error(file, "GLB header", "magic is \"gLTF\", expected \"glTF\"");
    // A JSON file named .glb is not a GLB either.
    write_text(file, tiny_character().gltf().dump());
    expect_error(file, "GLB header", "magic is \"{\\x22ac\"");
    // Nor is a text file named .vrm (VRM files are glTF binaries) or .GLB: the magic is
    // named, not the JSON parser's first byte.
    for (const char* name : {"avatar.vrm", "TINY.GLB"}) {
        const std::string other = dir.file(name);
        write_text(other, "not a model");
        expect_error(other, "GLB header", "magic is \"not \"");
    }
}

TEST(GltfImportErrors, AccessorOutOfRange) {
    TempDir dir;
    {
        Builder b = tiny_character();
        b.doc["accessors"][1]["count"] = 4;  // 4 VEC3 = 48 bytes in a 36-byte view
        expect_doc_error(dir, b.gltf(), "$.accessors[1]", "run past the end of bufferView 1 (36 bytes)");
    }
    {
        Builder b = tiny_character();
        b.doc["accessors"][1]["byteOffset"] = 4;
        expect_doc_error(dir, b.gltf(), "$.accessors[1]", "from byteOffset 4 run past the end");
    }
    {
        Builder b = tiny_character();
        b.doc["bufferViews"][1]["byteLength"] = 100000;  // past the buffer
        expect_doc_error(dir, b.gltf(), "$.bufferViews[1]", "run past the end of buffer 0");
    }
    {
        Builder b = tiny_character();
        b.doc["animations"][0]["samplers"][0]["output"] = 42;
        expect_doc_error(dir, b.gltf(), "$.animations[0].samplers[0].output", "accessor 42 does not exist");
    }
}

TEST(GltfImportErrors, NonInvertibleInverseBindMatrix) {
    TempDir dir;
    {
        Builder b = tiny_character();
        // A matrix scaling z by 0.
        const int singular = b.add({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, /**/ 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
                                   "MAT4");
        b.doc["skins"][0]["inverseBindMatrices"] = singular;
        expect_doc_error(dir, b.gltf(), "$.skins[0].inverseBindMatrices[0]", "joint node 0 is not invertible");
    }
    {
        Builder b = tiny_character();
        const float nan = std::nanf("");
        const int bad = b.add({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, /**/ nan, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
                              "MAT4");
        b.doc["skins"][0]["inverseBindMatrices"] = bad;
        expect_doc_error(dir, b.gltf(), "$.skins[0].inverseBindMatrices[1]", "is not a finite number");
    }
    {
        // Nearly singular relative to its size: columns of length 1, 1, 1 with the
        // third almost parallel to the first (|det| = 1e-8).
        Builder b = tiny_character();
        const float e = 1e-8f;
        const int bad = b.add({1, 0, 0, 0, 0, 1, 0, 0, 1, 0, e, 0, 0, 0, 0, 1, /**/ 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
                              "MAT4");
        b.doc["skins"][0]["inverseBindMatrices"] = bad;
        expect_doc_error(dir, b.gltf(), "$.skins[0].inverseBindMatrices[0]", "not invertible");
    }
    {
        // A small but proper scale (1e-3 on every axis, det 1e-9) is accepted: the test is
        // relative to the matrix's size.
        Builder b = tiny_character();
        const float s = 1e-3f;
        const int small = b.add({s, 0, 0, 0, 0, s, 0, 0, 0, 0, s, 0, 0, 0, 0, 1, /**/ 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
                                "MAT4");
        b.doc["skins"][0]["inverseBindMatrices"] = small;
        const std::string file = dir.file("small.gltf");
        write_text(file, b.gltf().dump());
        const auto loaded = gltf::load_character(file);
        EXPECT_TRUE(loaded.ok()) << loaded.error().message;
    }
}

TEST(GltfImportErrors, SkinJoints) {
    TempDir dir;
    {
        Builder b = tiny_character();
        b.doc["skins"][0]["joints"] = json::array();
        b.doc["skins"][0].erase("inverseBindMatrices");
        expect_doc_error(dir, b.gltf(), "$.skins[0].joints", "at least one joint");
    }
    {
        Builder b = tiny_character();
        b.doc["skins"][0]["joints"] = {0, 17};
        expect_doc_error(dir, b.gltf(), "$.skins[0].joints[1]", "node 17 does not exist");
    }
    {
        Builder b = tiny_character();
        b.doc["skins"][0]["joints"] = {0, 1, 0};  // three joints, two matrices
        expect_doc_error(dir, b.gltf(), "$.skins[0].inverseBindMatrices", "2 matrices for 3 joints");
    }
}

TEST(GltfImportErrors, NodeTreeCycles) {
    TempDir dir;
    {
        Builder b = tiny_character();
        b.doc["nodes"][0]["children"] = {0};
        expect_doc_error(dir, b.gltf(), "$.nodes[0].children[0]", "node 0 is its own child");
    }
    {
        Builder b = tiny_character();
        b.doc["nodes"][1]["children"] = {0};  // 0 -> 1 -> 0
        expect_doc_error(dir, b.gltf(), "$.nodes[1].children[0]", "node 0 is its own ancestor (cycle 0 -> 1 -> 0)");
    }
    {
        Builder b = tiny_character();
        b.doc["nodes"].push_back({{"name", "second parent"}, {"children", {1}}});
        expect_doc_error(dir, b.gltf(), "$.nodes[2].children[0]", "node 1 already has parent node 0");
    }
    {
        Builder b = tiny_character();
        b.doc["nodes"][1]["children"] = {5};
        expect_doc_error(dir, b.gltf(), "$.nodes[1].children[0]", "node 5 does not exist");
    }
}

TEST(GltfImportErrors, MissingExternalBuffer) {
    TempDir dir;
    const std::string file = dir.file("sphere-collider.gltf");
    fs::copy_file(kAssets + "/vrm-springbone/sphere-collider.gltf", file);
    expect_error(file, "$.buffers[0].uri", "external buffer \"sphere_mesh.bin\" not found");
    // Present but shorter than declared.
    write_bytes(dir.file("sphere_mesh.bin"), std::vector<unsigned char>(100, 0));
    expect_error(file, "$.buffers[0]", "has 100 bytes (truncated)");
}

TEST(GltfImportErrors, AnimationProblems) {
    TempDir dir;
    {
        Builder b = tiny_character();
        b.doc["animations"][0]["channels"][0]["target"]["node"] = 9;
        expect_doc_error(dir, b.gltf(), "$.animations[0].channels[0].target.node", "node 9 does not exist");
    }
    {
        Builder b = tiny_character();
        b.doc["animations"][0]["samplers"][0]["interpolation"] = "SMOOTH";
        // tinygltf may reject the value itself; either way the error names the sampler.
        const std::string file = dir.file("bad.gltf");
        write_text(file, b.gltf().dump());
        const auto loaded = gltf::load_character(file);
        ASSERT_FALSE(loaded.ok());
        EXPECT_EQ(loaded.error().message.rfind(file + ": ", 0), 0u) << loaded.error().message;
    }
    {
        Builder b = tiny_character();
        const int times = b.add({0.0f, 1.0f, 1.0f}, "SCALAR");
        b.doc["animations"][0]["samplers"][0]["input"] = times;
        expect_doc_error(dir, b.gltf(), "$.animations[0].samplers[0].input", "key times must increase");
    }
    {
        Builder b = tiny_character();
        b.doc["animations"][0]["channels"][0]["sampler"] = 2;  // a VEC4 rotation sampler on translation
        b.doc["animations"][0]["channels"][2]["sampler"] = 0;
        expect_doc_error(dir, b.gltf(), "$.animations[0].samplers[2].output", "translation or scale needs VEC3");
    }
    {
        Builder b = tiny_character();
        b.doc["nodes"][1].erase("translation");
        b.doc["nodes"][1]["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        expect_doc_error(dir, b.gltf(), "$.animations[0].channels[0].target.node", "has a matrix");
    }
}

}  // namespace
}  // namespace kodawari
