// The streamed .glb JSON (engine/export/gltf_json_stream.cpp): for random models, the
// file written with part of the nodes, accessors, channels and samplers given by
// generators and part of buffer 0 written as a tail is, byte for byte, what tinygltf
// writes for the whole model; and a failure leaves no file behind.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <algorithm>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>  // a system header: its warnings are not ours

#include "export/gltf_json_stream.hpp"
#include "test_support.hpp"

namespace kodawari {
namespace {

using testing_support::TempDir;

class Random {
public:
    explicit Random(std::uint32_t seed) : engine_(seed) {}
    int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(engine_); }
    bool chance(double p) { return std::bernoulli_distribution(p)(engine_); }
    // Numbers whose shortest text differs in kind: integers, fractions, tiny, huge, -0.
    double number() {
        switch (integer(0, 6)) {
            case 0: return static_cast<double>(integer(-5, 5));
            case 1: return -0.0;
            case 2: return std::uniform_real_distribution<double>(-1e-6, 1e-6)(engine_);
            case 3: return std::uniform_real_distribution<double>(-1e22, 1e22)(engine_);
            case 4: return static_cast<double>(static_cast<float>(std::uniform_real_distribution<double>(-1, 1)(engine_)));
            default: return std::uniform_real_distribution<double>(-100, 100)(engine_);
        }
    }
    std::vector<double> numbers(int n) {
        std::vector<double> values(static_cast<std::size_t>(n));
        for (double& v : values) v = number();
        return values;
    }
    // Names with what JSON escapes (quotes, backslashes, control characters) and UTF-8.
    std::string name(const std::string& base) {
        static const char* const kPieces[] = {"\"", "\\", "\n", "\t", "\x01", "\xc3\xa9", "/", " ", "\xe9\xb3\xa5"};
        std::string text = base;
        for (int i = integer(0, 3); i > 0; --i) text += kPieces[integer(0, 8)];
        return text;
    }
    tinygltf::Value value(int depth = 0) {
        switch (integer(0, depth > 1 ? 3 : 5)) {
            case 0: return tinygltf::Value(integer(-9, 9));
            case 1: return tinygltf::Value(number());
            case 2: return tinygltf::Value(chance(0.5));
            case 3: return tinygltf::Value(name("s"));
            case 4: {
                tinygltf::Value::Array array;
                for (int i = integer(0, 3); i > 0; --i) array.push_back(value(depth + 1));
                return tinygltf::Value(std::move(array));
            }
            default: {
                tinygltf::Value::Object object;
                for (int i = integer(0, 3); i > 0; --i) object[name("k")] = value(depth + 1);
                return tinygltf::Value(std::move(object));
            }
        }
    }

private:
    std::mt19937 engine_;
};

tinygltf::Node random_node(Random& r, int index, int nodes) {
    tinygltf::Node node;
    if (r.chance(0.7)) node.name = r.name("node" + std::to_string(index));
    if (r.chance(0.6)) node.translation = r.numbers(3);
    if (r.chance(0.6)) node.rotation = r.numbers(4);
    if (r.chance(0.3)) node.scale = r.numbers(3);
    if (r.chance(0.1)) node.matrix = r.numbers(16);
    if (r.chance(0.5)) node.mesh = 0;
    if (r.chance(0.1)) node.skin = r.integer(0, 3);
    if (r.chance(0.1)) node.camera = r.integer(0, 3);
    if (r.chance(0.1)) node.weights = r.numbers(2);
    if (r.chance(0.1)) node.extras = r.value();
    if (r.chance(0.1)) node.extensions["KHR_test"] = r.value();
    if (r.chance(0.05)) node.extensions["EXT_empty"] = tinygltf::Value();
    for (int child = index + 1; child < nodes; ++child) {
        if (r.chance(0.2)) node.children.push_back(child);
    }
    return node;
}

tinygltf::Accessor random_accessor(Random& r, int index) {
    static const int kComponents[] = {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                                      TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_DOUBLE};
    static const int kTypes[] = {TINYGLTF_TYPE_SCALAR, TINYGLTF_TYPE_VEC2, TINYGLTF_TYPE_VEC3, TINYGLTF_TYPE_VEC4,
                                 TINYGLTF_TYPE_MAT2,   TINYGLTF_TYPE_MAT3, TINYGLTF_TYPE_MAT4};
    tinygltf::Accessor accessor;
    accessor.bufferView = r.chance(0.9) ? r.integer(0, 1) : -1;
    accessor.byteOffset = r.chance(0.5) ? 0 : static_cast<std::size_t>(r.integer(1, 1 << 30));
    accessor.componentType = kComponents[r.integer(0, 3)];
    accessor.count = static_cast<std::size_t>(r.integer(1, 100000));
    accessor.type = kTypes[r.integer(0, 6)];
    accessor.normalized = r.chance(0.3);
    if (r.chance(0.5)) {
        const int n = r.integer(1, 4);
        accessor.minValues = r.numbers(n);
        accessor.maxValues = r.numbers(n);
        // Integer bounds are written as ints: keep them where the cast is defined.
        for (double& v : accessor.minValues) v = std::fmod(v, 1e9);
        for (double& v : accessor.maxValues) v = std::fmod(v, 1e9);
    }
    if (r.chance(0.3)) accessor.name = r.name("accessor" + std::to_string(index));
    if (r.chance(0.1)) accessor.extras = r.value();
    if (r.chance(0.1)) {
        accessor.sparse.isSparse = true;
        accessor.sparse.count = r.integer(1, 9);
        accessor.sparse.indices.bufferView = 1;
        accessor.sparse.indices.byteOffset = r.integer(0, 64);
        accessor.sparse.indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
        accessor.sparse.values.bufferView = 0;
        accessor.sparse.values.byteOffset = r.integer(0, 64);
    }
    return accessor;
}

tinygltf::Animation random_animation(Random& r, const std::string& name, int channels, int nodes, int accessors) {
    static const char* const kPaths[] = {"translation", "rotation", "scale", "weights"};
    tinygltf::Animation animation;
    animation.name = name;
    if (r.chance(0.3)) animation.extras = r.value();
    for (int i = 0; i < channels; ++i) {
        tinygltf::AnimationSampler sampler;
        sampler.input = r.integer(0, accessors - 1);
        sampler.output = r.integer(0, accessors - 1);
        sampler.interpolation = r.chance(0.5) ? "LINEAR" : "STEP";
        if (r.chance(0.1)) sampler.extras = r.value();
        animation.samplers.push_back(sampler);
        tinygltf::AnimationChannel channel;
        channel.sampler = i;
        channel.target_node = r.integer(0, nodes - 1);
        channel.target_path = kPaths[r.integer(0, 3)];
        if (r.chance(0.1)) channel.extras = r.value();
        if (r.chance(0.1)) channel.extensions["KHR_c"] = r.value();
        if (r.chance(0.1)) channel.target_extensions["KHR_t"] = r.value();
        animation.channels.push_back(channel);
    }
    return animation;
}

// A skin of random joints, with or without inverse bind matrices, skeleton and name.
tinygltf::Skin random_skin(Random& r, int nodes, int accessors) {
    tinygltf::Skin skin;
    const int joints = r.integer(1, 8);
    for (int j = 0; j < joints; ++j) skin.joints.push_back(r.integer(0, nodes - 1));
    if (accessors > 0 && r.chance(0.7)) skin.inverseBindMatrices = r.integer(0, accessors - 1);
    if (r.chance(0.5)) skin.skeleton = r.integer(0, nodes - 1);
    if (r.chance(0.7)) skin.name = r.name("skin");
    return skin;
}

// A whole model: every part a writer uses, and its buffer's bytes.
tinygltf::Model random_model(Random& r, int nodes, int accessors, int channels, std::size_t buffer_bytes) {
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = r.name("test");
    if (buffer_bytes > 0 || r.chance(0.8)) {
        model.buffers.emplace_back();
        model.buffers[0].data.resize(buffer_bytes);
        for (unsigned char& byte : model.buffers[0].data) byte = static_cast<unsigned char>(r.integer(0, 255));
        for (int i = 0; i < 2; ++i) {
            tinygltf::BufferView view;
            view.buffer = 0;
            view.byteOffset = static_cast<std::size_t>(i * 8);
            view.byteLength = buffer_bytes / 2;
            view.target = i == 0 ? TINYGLTF_TARGET_ARRAY_BUFFER : 0;
            model.bufferViews.push_back(view);
        }
    }
    tinygltf::Material material;
    material.name = r.name("material");
    material.pbrMetallicRoughness.baseColorFactor = {0.25, 0.5, 1.0, 1.0};
    model.materials.push_back(material);
    tinygltf::Mesh mesh;
    mesh.name = r.name("mesh");
    tinygltf::Primitive primitive;
    primitive.material = 0;
    primitive.attributes["POSITION"] = 0;
    mesh.primitives.push_back(primitive);
    model.meshes.push_back(mesh);
    for (int i = 0; i < nodes; ++i) model.nodes.push_back(random_node(r, i, nodes));
    for (int i = 0; i < accessors; ++i) model.accessors.push_back(random_accessor(r, i));
    const int skins = nodes > 0 ? r.integer(0, 5) : 0;
    for (int i = 0; i < skins; ++i) model.skins.push_back(random_skin(r, nodes, accessors));
    if (channels > 0) {
        model.animations.push_back(random_animation(r, r.name("flight"), channels, std::max(nodes, 1), std::max(accessors, 1)));
        if (r.chance(0.5)) model.animations.push_back(random_animation(r, "second", r.integer(0, 3), std::max(nodes, 1), std::max(accessors, 1)));
    }
    tinygltf::Scene scene;
    scene.name = r.name("scene");
    if (nodes > 0) scene.nodes.push_back(0);
    model.scenes.push_back(scene);
    model.defaultScene = 0;
    return model;
}

std::string tinygltf_glb(tinygltf::Model& model) {
    std::ostringstream stream;
    tinygltf::TinyGLTF writer;
    EXPECT_TRUE(writer.WriteGltfSceneToStream(&model, stream, false, true));
    return std::move(stream).str();
}

// Moves `all`'s elements from `keep` on into a source of groups of 0 to 3.
template <typename T>
gltf::ElementSource<T> split(Random& r, std::vector<T>& all, std::size_t keep,
                             std::shared_ptr<std::vector<std::vector<T>>>& groups) {
    groups = std::make_shared<std::vector<std::vector<T>>>();
    for (std::size_t i = keep; i < all.size();) {
        const std::size_t n = std::min<std::size_t>(all.size() - i, static_cast<std::size_t>(r.integer(0, 3)));
        groups->emplace_back(all.begin() + static_cast<std::ptrdiff_t>(i), all.begin() + static_cast<std::ptrdiff_t>(i + n));
        i += n;
    }
    all.resize(std::min(keep, all.size()));
    gltf::ElementSource<T> source;
    source.groups = groups->size();
    source.fill = [g = groups](std::size_t group, std::vector<T>& out) {
        out.insert(out.end(), (*g)[group].begin(), (*g)[group].end());
    };
    return source;
}

struct Streamed {
    gltf::StreamedElements elements;
    std::shared_ptr<std::vector<std::vector<tinygltf::Node>>> nodes;
    std::shared_ptr<std::vector<std::vector<tinygltf::Accessor>>> accessors;
    std::shared_ptr<std::vector<std::vector<tinygltf::Skin>>> skins;
    std::shared_ptr<std::vector<std::vector<tinygltf::AnimationChannel>>> channels;
    std::shared_ptr<std::vector<std::vector<tinygltf::AnimationSampler>>> samplers;
};

// Compares the streamed file with tinygltf's for one random model; `keep_*` < 0: a random
// split.
void check_identical(std::uint32_t seed, int nodes, int accessors, int channels, std::size_t buffer_bytes,
                     int keep_nodes, int keep_accessors, int keep_channels, std::size_t tail_bytes) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Random r(seed);
    tinygltf::Model model = random_model(r, nodes, accessors, channels, buffer_bytes);
    const std::string expected = tinygltf_glb(model);

    const auto keep = [&](int k, int n) { return static_cast<std::size_t>(k >= 0 ? k : r.integer(0, n)); };
    Streamed s;
    s.elements.nodes = split(r, model.nodes, keep(keep_nodes, nodes), s.nodes);
    s.elements.accessors = split(r, model.accessors, keep(keep_accessors, accessors), s.accessors);
    const int skins = static_cast<int>(model.skins.size());
    s.elements.skins = split(r, model.skins, keep(keep_nodes >= 0 ? std::min(keep_nodes, skins) : -1, skins), s.skins);
    if (!model.animations.empty()) {
        s.elements.channels = split(r, model.animations[0].channels, keep(keep_channels, channels), s.channels);
        s.elements.samplers = split(r, model.animations[0].samplers, keep(keep_channels, channels), s.samplers);
    }
    std::vector<unsigned char> tail;
    if (!model.buffers.empty()) {
        std::vector<unsigned char>& data = model.buffers[0].data;
        const std::size_t cut = data.size() - std::min(tail_bytes, data.size());
        tail.assign(data.begin() + static_cast<std::ptrdiff_t>(cut), data.end());
        data.resize(cut);
    }

    const std::size_t kept_channels = model.animations.empty() ? 0 : model.animations[0].channels.size();
    TempDir dir;
    const std::string path = dir.file("streamed.glb");
    {
        auto file = AtomicFile::open(path);
        ASSERT_TRUE(file.ok());
        auto written = gltf::write_streamed_glb(file.value(), model, s.elements, tail.size(), [&]() -> Result<void> {
            file.value().write(tail.data(), tail.size());
            return {};
        });
        ASSERT_TRUE(written.ok()) << written.error().message;
        ASSERT_TRUE(file.value().commit().ok());
    }
    const std::string actual = testing_support::file_bytes(path);
    ASSERT_EQ(actual.size(), expected.size());
    EXPECT_TRUE(actual == expected) << "first difference at byte "
                                    << std::distance(actual.begin(), std::mismatch(actual.begin(), actual.end(), expected.begin()).first);
    // The model the caller gave is as it was (buffer bytes held out, stand-in channel).
    if (!model.buffers.empty()) {
        EXPECT_EQ(model.buffers[0].data.size(), buffer_bytes - tail.size());
    }
    if (!model.animations.empty()) {
        EXPECT_EQ(model.animations[0].channels.size(), kept_channels);
    }
    EXPECT_EQ(dir.entries().size(), 1u);  // no spill file left
}

TEST(JsonStream, RandomModelsAreTinygltfsBytes) {
    for (std::uint32_t seed = 1; seed <= 60; ++seed) {
        Random r(seed * 7919u);
        const int nodes = r.integer(0, 40);
        const int accessors = r.integer(0, 40);
        const int channels = r.integer(0, 20);
        const std::size_t buffer = static_cast<std::size_t>(r.integer(0, 300));
        check_identical(seed, nodes, accessors, channels, buffer, -1, -1, -1, static_cast<std::size_t>(r.integer(0, 300)));
    }
}

TEST(JsonStream, EverythingStreamed) {
    // Arrays the model does not have at all, and an animation whose channels are all
    // streamed (tinygltf would leave out an animation without channels).
    for (std::uint32_t seed = 100; seed < 110; ++seed) check_identical(seed, 25, 30, 12, 200, 0, 0, 0, 150);
}

TEST(JsonStream, NothingStreamed) {
    for (std::uint32_t seed = 200; seed < 205; ++seed) check_identical(seed, 25, 30, 12, 203, 25, 30, 12, 0);
    check_identical(205, 0, 0, 0, 0, 0, 0, 0, 0);  // an empty model: no BIN chunk
}

TEST(JsonStream, WholeBufferAsTail) {
    check_identical(300, 10, 10, 4, 1001, -1, -1, -1, 1001);
}

// tinygltf writes int(byteOffset), negative past 2 GiB; the streamed file the offset.
TEST(JsonStream, AccessorOffsetsPast2GiB) {
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.buffers.emplace_back();
    model.buffers[0].data.resize(8);
    gltf::StreamedElements streamed;
    streamed.accessors.groups = 1;
    streamed.accessors.fill = [](std::size_t, std::vector<tinygltf::Accessor>& out) {
        tinygltf::Accessor accessor;
        accessor.bufferView = 0;
        accessor.byteOffset = 3'000'000'000u;
        accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
        accessor.count = 1;
        accessor.type = TINYGLTF_TYPE_SCALAR;
        out.push_back(accessor);
    };
    TempDir dir;
    auto file = AtomicFile::open(dir.file("big.glb"));
    ASSERT_TRUE(file.ok());
    ASSERT_TRUE(gltf::write_streamed_glb(file.value(), model, streamed, 0, {}).ok());
    ASSERT_TRUE(file.value().commit().ok());
    const std::string glb = testing_support::file_bytes(dir.file("big.glb"));
    std::uint32_t json_length = 0;
    std::memcpy(&json_length, glb.data() + 12, 4);
    const auto json = nlohmann::json::parse(glb.substr(20, json_length));
    EXPECT_EQ(json["accessors"][0]["byteOffset"].get<std::uint64_t>(), 3'000'000'000u);
}

// A failure while writing (here the tail, a generator, the size) leaves neither the file
// nor its temporary files.
TEST(JsonStream, FailureLeavesNoFile) {
    Random r(17);
    TempDir dir;
    const std::string path = dir.file("failed.glb");
    const auto streamed_nodes = [](bool throw_at_end) {
        gltf::StreamedElements streamed;
        streamed.nodes.groups = 1000;
        streamed.nodes.fill = [throw_at_end](std::size_t group, std::vector<tinygltf::Node>& out) {
            if (throw_at_end && group == 999) throw std::runtime_error("generator failed");
            out.emplace_back();
            out.back().name = "n" + std::to_string(group);
        };
        return streamed;
    };
    {
        tinygltf::Model model = random_model(r, 3, 3, 2, 64);
        auto file = AtomicFile::open(path);
        ASSERT_TRUE(file.ok());
        auto written = gltf::write_streamed_glb(file.value(), model, streamed_nodes(false), 100,
                                                [] { return Result<void>(make_error(Error::Kind::Io, "disk full")); });
        ASSERT_FALSE(written.ok());
        EXPECT_EQ(written.error().message, "disk full");
    }
    EXPECT_TRUE(dir.entries().empty());
    {
        tinygltf::Model model = random_model(r, 3, 3, 2, 64);
        auto file = AtomicFile::open(path);
        ASSERT_TRUE(file.ok());
        EXPECT_THROW((void)gltf::write_streamed_glb(file.value(), model, streamed_nodes(true), 0, {}), std::runtime_error);
        // The model is given back as it was, even so.
        EXPECT_EQ(model.buffers[0].data.size(), 64u);
    }
    EXPECT_TRUE(dir.entries().empty());
    {
        tinygltf::Model model = random_model(r, 3, 3, 2, 64);
        auto file = AtomicFile::open(path);
        ASSERT_TRUE(file.ok());
        bool tail_written = false;
        auto written = gltf::write_streamed_glb(file.value(), model, streamed_nodes(false), 5'000'000'000ull, [&] {
            tail_written = true;
            return Result<void>();
        });
        ASSERT_FALSE(written.ok());
        EXPECT_NE(written.error().message.find("4 GiB"), std::string::npos) << written.error().message;
        EXPECT_FALSE(tail_written);
    }
    EXPECT_TRUE(dir.entries().empty());
    {
        // Streamed channels need the animation they belong to.
        tinygltf::Model model = random_model(r, 3, 3, 0, 64);
        gltf::StreamedElements streamed;
        streamed.channels.groups = 1;
        streamed.channels.fill = [](std::size_t, std::vector<tinygltf::AnimationChannel>& out) { out.emplace_back(); };
        auto file = AtomicFile::open(path);
        ASSERT_TRUE(file.ok());
        auto written = gltf::write_streamed_glb(file.value(), model, streamed, 0, {});
        ASSERT_FALSE(written.ok());
        EXPECT_EQ(written.error().kind, Error::Kind::InvalidInput);
    }
    EXPECT_TRUE(dir.entries().empty());
}

}  // namespace
}  // namespace kodawari
