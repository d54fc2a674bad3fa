#pragma once
// What the glTF import suites share: hand-built glTF documents with known values (Builder,
// tiny_character), file helpers, and the check of an import error's file, path and words.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include <tiny_gltf.h>  // a system header: its warnings are not ours

#include "kodawari/animation/character.hpp"
#include "kodawari/gltf/import.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"


namespace kodawari::gltf_import_test {

using testing_support::base64;

namespace fs = std::filesystem;
using nlohmann::json;

inline const std::string kAssets = std::string(KODAWARI_SOURCE_DIR) + "/tests/assets";
inline const std::string kRiggedSimple = kAssets + "/khronos/RiggedSimple.gltf";

inline json read_json(const std::string& path) {
    std::ifstream in(path);
    return json::parse(in);
}

using testing_support::TempDir;

inline void write_bytes(const std::string& path, const std::vector<unsigned char>& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

inline void write_text(const std::string& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
}

inline std::vector<unsigned char> read_all(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A buffer of floats under construction; each add() returns the index of a new
// bufferView + accessor holding them.
struct Builder {
    json doc;
    std::vector<unsigned char> bytes;

    Builder() {
        doc["asset"] = {{"version", "2.0"}};
        doc["bufferViews"] = json::array();
        doc["accessors"] = json::array();
    }

    int add(const std::vector<float>& values, const std::string& type) {
        const std::size_t offset = bytes.size();
        bytes.resize(offset + values.size() * sizeof(float));
        std::memcpy(bytes.data() + offset, values.data(), values.size() * sizeof(float));
        const std::size_t comps = type == "SCALAR" ? 1 : type == "VEC3" ? 3 : type == "VEC4" ? 4 : 16;
        doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", values.size() * 4}});
        doc["accessors"].push_back({{"bufferView", doc["bufferViews"].size() - 1},
                                    {"componentType", 5126},
                                    {"count", values.size() / comps},
                                    {"type", type}});
        return static_cast<int>(doc["accessors"].size() - 1);
    }

    // The document with its buffer as a data URI (§3.6.1).
    [[nodiscard]] json gltf() const {
        json d = doc;
        d["buffers"] = json::array({{{"byteLength", bytes.size()},
                                     {"uri", "data:application/octet-stream;base64," + base64(bytes)}}});
        return d;
    }

    // The same as a .glb: header, JSON chunk, BIN chunk (§4 GLB File Format).
    [[nodiscard]] std::vector<unsigned char> glb() const {
        json d = doc;
        d["buffers"] = json::array({{{"byteLength", bytes.size()}}});
        std::string text = d.dump();
        while (text.size() % 4 != 0) text += ' ';
        std::vector<unsigned char> bin = bytes;
        while (bin.size() % 4 != 0) bin.push_back(0);
        std::vector<unsigned char> out;
        auto u32 = [&](std::uint32_t v) {
            for (int i = 0; i < 4; ++i) out.push_back(static_cast<unsigned char>(v >> (8 * i)));
        };
        u32(0x46546C67u);
        u32(2);
        u32(static_cast<std::uint32_t>(12 + 8 + text.size() + 8 + bin.size()));
        u32(static_cast<std::uint32_t>(text.size()));
        u32(0x4E4F534Au);
        out.insert(out.end(), text.begin(), text.end());
        u32(static_cast<std::uint32_t>(bin.size()));
        u32(0x004E4942u);
        out.insert(out.end(), bin.begin(), bin.end());
        return out;
    }
};

// Two nodes (root 0 with child 1), a skin of both, and three animations:
//   0: times {0, 1, 3} on node 1: LINEAR translation, STEP scale, LINEAR rotation
//   1: times {0, 2} CUBICSPLINE translation and rotation of node 1
inline Builder tiny_character() {
    Builder b;
    const int times = b.add({0.0f, 1.0f, 3.0f}, "SCALAR");
    const int translations = b.add({0, 0, 0, 2, 4, -6, 2, 0, 0}, "VEC3");
    const int scales = b.add({1, 1, 1, 2, 2, 2, 3, 3, 3}, "VEC3");
    // 0, 180 degrees about z, then (0, 0, -0.6, -0.8): the same rotation as
    // (0, 0, 0.6, 0.8), on the far side of the sphere, so the shorter arc needs a flip.
    const int rotations = b.add({0, 0, 0, 1, 0, 0, 1, 0, 0, 0, -0.6f, -0.8f}, "VEC4");
    const int cubic_times = b.add({0.0f, 2.0f}, "SCALAR");
    // Per key: in-tangent, value, out-tangent.
    const int cubic_translations = b.add({9, 9, 9, 0, 1, 0, 1, 0, 2, /**/ 3, -1, 0, 1, 3, -1, 9, 9, 9}, "VEC3");
    const int cubic_rotations = b.add({0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, /**/ 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0}, "VEC4");
    const int ibm = b.add({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, /**/ 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1},
                          "MAT4");
    b.doc["scene"] = 0;
    b.doc["scenes"] = json::array({{{"nodes", {0}}}});
    b.doc["nodes"] = json::array({{{"name", "root"}, {"children", {1}}, {"translation", {0, 1, 0}}},
                                  {{"name", "tip"}, {"translation", {0, 1, 0}}}});
    b.doc["skins"] = json::array({{{"joints", {0, 1}}, {"inverseBindMatrices", ibm}, {"skeleton", 0}}});
    b.doc["animations"] = json::array(
        {{{"name", "keys"},
          {"samplers",
           {{{"input", times}, {"output", translations}, {"interpolation", "LINEAR"}},
            {{"input", times}, {"output", scales}, {"interpolation", "STEP"}},
            {{"input", times}, {"output", rotations}, {"interpolation", "LINEAR"}}}},
          {"channels",
           {{{"sampler", 0}, {"target", {{"node", 1}, {"path", "translation"}}}},
            {{"sampler", 1}, {"target", {{"node", 1}, {"path", "scale"}}}},
            {{"sampler", 2}, {"target", {{"node", 1}, {"path", "rotation"}}}}}}},
         {{"name", "cubic"},
          {"samplers",
           {{{"input", cubic_times}, {"output", cubic_translations}, {"interpolation", "CUBICSPLINE"}},
            {{"input", cubic_times}, {"output", cubic_rotations}, {"interpolation", "CUBICSPLINE"}}}},
          {"channels",
           {{{"sampler", 0}, {"target", {{"node", 1}, {"path", "translation"}}}},
            {{"sampler", 1}, {"target", {{"node", 1}, {"path", "rotation"}}}}}}}});
    return b;
}

inline animation::Character load_ok(const std::string& path) {
    auto loaded = gltf::load_character(path);
    EXPECT_TRUE(loaded.ok()) << (loaded.ok() ? "" : loaded.error().message);
    if (!loaded.ok()) return {};
    return std::move(loaded).value();
}

// The error of loading `doc` (written as `name`): it must fail with `kind`, and its
// message must start with the file and contain `expected_path` and `words`.
inline void expect_error(const std::string& file, const std::string& expected_path, const std::string& words,
                  Error::Kind kind = Error::Kind::InvalidInput) {
    const auto loaded = gltf::load_character(file);
    ASSERT_FALSE(loaded.ok()) << file << " loaded";
    const std::string& message = loaded.error().message;
    EXPECT_EQ(loaded.error().kind, kind) << message;
    EXPECT_EQ(message.rfind(file + ": " + expected_path + ": ", 0), 0u) << message;
    EXPECT_NE(message.find(words), std::string::npos) << message;
}

inline void expect_doc_error(const TempDir& dir, const json& doc, const std::string& expected_path, const std::string& words,
                      Error::Kind kind = Error::Kind::InvalidInput) {
    const std::string file = dir.file("bad.gltf");
    write_text(file, doc.dump());
    expect_error(file, expected_path, words, kind);
}

// Double-precision local matrix of a tinygltf node (§3.5.3), with the TRS overridden
// when given.
inline glm::dmat4 raw_local(const tinygltf::Node& node) {
    if (node.matrix.size() == 16) {
        glm::dmat4 m(1.0);
        for (int c = 0; c < 4; ++c) {
            for (int r = 0; r < 4; ++r) m[c][r] = node.matrix[static_cast<std::size_t>(4 * c + r)];
        }
        return m;
    }
    glm::dvec3 t(0.0);
    glm::dquat q(1.0, 0.0, 0.0, 0.0);
    glm::dvec3 s(1.0);
    if (node.translation.size() == 3) t = {node.translation[0], node.translation[1], node.translation[2]};
    if (node.rotation.size() == 4) q = glm::dquat(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
    if (node.scale.size() == 3) s = {node.scale[0], node.scale[1], node.scale[2]};
    glm::dmat4 m = glm::mat4_cast(q);
    for (int c = 0; c < 3; ++c) m[c] *= s[c];
    m[3] = glm::dvec4(t, 1.0);
    return m;
}

inline double max_abs_diff(const glm::mat4& a, const glm::dmat4& b) {
    double d = 0.0;
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) d = std::max(d, std::abs(static_cast<double>(a[c][r]) - b[c][r]));
    }
    return d;
}


}  // namespace kodawari::gltf_import_test
