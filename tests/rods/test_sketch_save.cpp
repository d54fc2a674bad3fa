// Sketching's save-back (SPEC A.6, docs/sketch.md): a sketched view example spliced into
// the scene's text and undone, refusals of what the loader would not take, the checked
// write (never over a file the scene reads) and a scene moved to another folder.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "kodawari/core/atomic_file.hpp"
#include "kodawari/rods/shape.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/scene/scene_edit.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

namespace kodawari {
namespace {

using Json = nlohmann::ordered_json;

std::string ahoge_path() { return std::string(KODAWARI_SOURCE_DIR) + "/scenes/ahoge.json"; }

// A view example for ahoge's 12-joint chain, from a sketch-like direction.
ViewSpec some_view(glm::vec3 direction) {
    ViewSpec v;
    v.view.direction = glm::normalize(direction);
    v.view.influence = 7.5f;
    for (int i = 0; i < 12; ++i) {
        const double a = 0.2 * i;
        v.shape.positions.push_back(glm::vec3(0.01 * std::sin(a) * i, 0.0127 * i, 0.0f));
    }
    v.shape.positions[0] = glm::vec3(0.0f);
    for (int i = 0; i < 12; ++i) {
        const int seg = std::min(i, 10);
        v.shape.orientations.push_back(rods::shortest_arc(
            glm::vec3(0.0f, 1.0f, 0.0f), glm::normalize(v.shape.positions[seg + 1] - v.shape.positions[seg])));
    }
    return v;
}

const ChainSpec& ahoge_chain(const Scene& scene) { return scene.characters.at(0).chains.at(0); }

TEST(SketchSave, AppendsAViewExampleAndUndoGivesTheFileBack) {
    const std::string text = testing_support::file_bytes(ahoge_path());
    const ViewSpec view = some_view({1.0f, 1.0f, 1.0f});  // 55 degrees from every example
    auto edit = add_view_example(text, "ahoge.json", "girl/ahoge", view);
    ASSERT_TRUE(edit.ok()) << edit.error().message;
    EXPECT_EQ(edit.value().index, 5u);
    EXPECT_EQ(edit.value().name, "sketch 1");
    EXPECT_FALSE(edit.value().replaced);

    auto scene = parse_scene(edit.value().text, ahoge_path());
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const ChainSpec& chain = ahoge_chain(scene.value());
    ASSERT_EQ(chain.views.size(), 6u);
    const ViewSpec& added = chain.views.back();
    EXPECT_EQ(added.name, "sketch 1");
    EXPECT_FLOAT_EQ(added.view.influence, 7.5f);
    EXPECT_LT(glm::length(added.view.direction - view.view.direction), 1e-5f);
    for (std::size_t i = 0; i < 12; ++i) {
        EXPECT_LT(glm::length(added.shape.positions[i] - view.shape.positions[i]), 1e-6f) << i;
        EXPECT_LT(glm::length(glm::vec4(added.shape.orientations[i].x - view.shape.orientations[i].x,
                                        added.shape.orientations[i].y - view.shape.orientations[i].y,
                                        added.shape.orientations[i].z - view.shape.orientations[i].z,
                                        added.shape.orientations[i].w - view.shape.orientations[i].w)),
                  1e-5f);
    }

    // Everything else is as it was: the JSON without the new example equals the original.
    Json after = Json::parse(edit.value().text);
    after["characters"][0]["chains"][0]["views"].erase(5);
    EXPECT_EQ(after, Json::parse(text));
    // And the original's bytes are all there, in order, around the insertion.
    EXPECT_EQ(edit.value().text.size() > text.size(), true);

    // A second sketch is "sketch 2"; undo removes it first, then "sketch 1".
    auto second = add_view_example(edit.value().text, "ahoge.json", "girl/ahoge", some_view({-1.0f, 1.0f, 1.0f}));
    ASSERT_TRUE(second.ok()) << second.error().message;
    EXPECT_EQ(second.value().name, "sketch 2");
    auto undo2 = remove_last_sketch(second.value().text, "ahoge.json", "girl/ahoge");
    ASSERT_TRUE(undo2.ok()) << undo2.error().message;
    EXPECT_EQ(undo2.value().name, "sketch 2");
    EXPECT_EQ(undo2.value().text, edit.value().text);
    auto undo1 = remove_last_sketch(undo2.value().text, "ahoge.json", "girl/ahoge");
    ASSERT_TRUE(undo1.ok()) << undo1.error().message;
    EXPECT_EQ(undo1.value().text, text);  // byte for byte
    auto nothing = remove_last_sketch(text, "ahoge.json", "girl/ahoge");
    ASSERT_FALSE(nothing.ok());
    EXPECT_NE(nothing.error().message.find("$.characters[0].chains[0].views"), std::string::npos)
        << nothing.error().message;
}

TEST(SketchSave, ReplacesAnExampleForNearlyTheSameView) {
    const std::string text = testing_support::file_bytes(ahoge_path());
    auto edit = add_view_example(text, "ahoge.json", "girl/ahoge", some_view({0.0f, 0.2f, 1.0f}));  // 11 deg from "front"
    ASSERT_TRUE(edit.ok()) << edit.error().message;
    EXPECT_TRUE(edit.value().replaced);
    EXPECT_EQ(edit.value().replaced_name, "front");
    EXPECT_EQ(edit.value().index, 0u);
    auto scene = parse_scene(edit.value().text, ahoge_path());
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    ASSERT_EQ(ahoge_chain(scene.value()).views.size(), 5u);
    EXPECT_EQ(ahoge_chain(scene.value()).views[0].name, "sketch 1");
    EXPECT_EQ(ahoge_chain(scene.value()).views[1].name, "back");

    // Issue 37: the replaced example is kept as the sketch's "replaces" and an undo puts it
    // back, byte for byte; a sketch replacing that sketch nests, and two undos unwind both.
    EXPECT_NE(edit.value().text.find("\"replaces\": {\"name\": \"front\""), std::string::npos);
    auto again = add_view_example(edit.value().text, "ahoge.json", "girl/ahoge", some_view({0.0f, 0.1f, 1.0f}));
    ASSERT_TRUE(again.ok()) << again.error().message;
    EXPECT_EQ(again.value().replaced_name, "sketch 1");
    ASSERT_TRUE(parse_scene(again.value().text, ahoge_path()).ok());
    auto undo2 = remove_last_sketch(again.value().text, "ahoge.json", "girl/ahoge");
    ASSERT_TRUE(undo2.ok()) << undo2.error().message;
    EXPECT_TRUE(undo2.value().replaced);
    EXPECT_EQ(undo2.value().replaced_name, "sketch 1");
    EXPECT_EQ(undo2.value().text, edit.value().text);
    auto undo1 = remove_last_sketch(undo2.value().text, "ahoge.json", "girl/ahoge");
    ASSERT_TRUE(undo1.ok()) << undo1.error().message;
    EXPECT_EQ(undo1.value().replaced_name, "front");
    EXPECT_EQ(undo1.value().text, text);  // byte for byte
}

TEST(SketchSave, AReplacedExampleTheLoaderWouldRefuseIsRefused) {
    // The kept example is checked as a view of the chain, so an undo never writes what the
    // loader refuses: one with a negative influence is an error naming its JSON path.
    const std::string text = testing_support::file_bytes(ahoge_path());
    auto edit = add_view_example(text, "ahoge.json", "girl/ahoge", some_view({0.0f, 0.2f, 1.0f}));
    ASSERT_TRUE(edit.ok()) << edit.error().message;
    Json scene = Json::parse(edit.value().text);
    Json& kept = scene["characters"][0]["chains"][0]["views"][0]["replaces"];
    ASSERT_TRUE(kept.is_object());
    kept["influence"] = -1;
    auto loaded = parse_scene(scene.dump(2), ahoge_path());
    ASSERT_FALSE(loaded.ok());
    EXPECT_NE(loaded.error().message.find("$.characters[0].chains[0].views[0].replaces.influence"), std::string::npos)
        << loaded.error().message;
}

TEST(SketchSave, AChainWithoutViewsGetsAViewsArrayAndUndoRemovesIt) {
    Json scene = Json::parse(testing_support::file_bytes(ahoge_path()));
    scene["characters"][0]["chains"][0].erase("views");
    const std::string text = scene.dump(2) + "\n";
    auto edit = add_view_example(text, "plain.json", "girl/ahoge", some_view({0.0f, 0.0f, 1.0f}));
    ASSERT_TRUE(edit.ok()) << edit.error().message;
    EXPECT_EQ(edit.value().index, 0u);
    auto loaded = parse_scene(edit.value().text, ahoge_path());
    ASSERT_TRUE(loaded.ok()) << loaded.error().message << "\n" << edit.value().text;
    EXPECT_EQ(ahoge_chain(loaded.value()).views.size(), 1u);
    auto undo = remove_last_sketch(edit.value().text, "plain.json", "girl/ahoge");
    ASSERT_TRUE(undo.ok()) << undo.error().message;
    EXPECT_EQ(undo.value().text, text);
}

// A fuzzing finding: with `"views": [` blank lines `]`, undo removed the whole member.
TEST(SketchSave, AnEmptyViewsArrayKeepsItsWhitespaceThroughAnUndo) {
    Json scene = Json::parse(testing_support::file_bytes(ahoge_path()));
    scene["characters"][0]["chains"][0]["views"] = Json::array();
    const std::string compact = scene.dump(2) + "\n";  // nlohmann writes "views": []
    const std::string spaced = std::regex_replace(compact, std::regex("\"views\": \\[\\]"), "\"views\": [\n\n      ]");
    ASSERT_NE(spaced, compact);
    auto edit = add_view_example(spaced, "spaced.json", "girl/ahoge", some_view({0.0f, 0.0f, 1.0f}));
    ASSERT_TRUE(edit.ok()) << edit.error().message;
    auto undo = remove_last_sketch(edit.value().text, "spaced.json", "girl/ahoge");
    ASSERT_TRUE(undo.ok()) << undo.error().message;
    EXPECT_EQ(undo.value().text, spaced);  // byte for byte

    // `[]` with nothing inside: after the add, the text is the same as for a chain without
    // `views`, so the undo takes the member (documented in scene_edit.hpp).
    auto edit2 = add_view_example(compact, "compact.json", "girl/ahoge", some_view({0.0f, 0.0f, 1.0f}));
    ASSERT_TRUE(edit2.ok()) << edit2.error().message;
    auto undo2 = remove_last_sketch(edit2.value().text, "compact.json", "girl/ahoge");
    ASSERT_TRUE(undo2.ok()) << undo2.error().message;
    scene["characters"][0]["chains"][0].erase("views");
    EXPECT_EQ(undo2.value().text, scene.dump(2) + "\n");
}

TEST(SketchSave, RefusesAMirrorAnUnknownChainAndAFullChain) {
    const std::string bunny = testing_support::file_bytes(std::string(KODAWARI_SOURCE_DIR) + "/scenes/bunny.json");
    auto mirror = add_view_example(bunny, "bunny.json", "bunny/ear_r", some_view({0.0f, 0.0f, 1.0f}));
    ASSERT_FALSE(mirror.ok());
    EXPECT_NE(mirror.error().message.find("mirror"), std::string::npos) << mirror.error().message;
    EXPECT_NE(mirror.error().message.find("bunny/ear_l"), std::string::npos) << mirror.error().message;
    EXPECT_NE(mirror.error().message.find("bunny.json: $.characters[0].chains["), std::string::npos)
        << mirror.error().message;

    const std::string text = testing_support::file_bytes(ahoge_path());
    auto unknown = add_view_example(text, "ahoge.json", "girl/tail", some_view({0.0f, 0.0f, 1.0f}));
    ASSERT_FALSE(unknown.ok());
    EXPECT_NE(unknown.error().message.find("ahoge.json: $.characters[0].chains: character \"girl\" has no chain \"tail\""),
              std::string::npos)
        << unknown.error().message;
    auto bad_id = add_view_example(text, "ahoge.json", "ahoge", some_view({0.0f, 0.0f, 1.0f}));
    ASSERT_FALSE(bad_id.ok());
    EXPECT_NE(bad_id.error().message.find("CHARACTER/CHAIN"), std::string::npos) << bad_id.error().message;

    // ahoge has 5 examples: two more fill it, the next one (not near any) is refused.
    auto six = add_view_example(text, "ahoge.json", "girl/ahoge", some_view({1.0f, 1.0f, 1.0f}));
    ASSERT_TRUE(six.ok());
    auto seven = add_view_example(six.value().text, "ahoge.json", "girl/ahoge", some_view({-1.0f, 1.0f, 1.0f}));
    ASSERT_TRUE(seven.ok());
    ASSERT_TRUE(parse_scene(seven.value().text, ahoge_path()).ok());
    auto eight = add_view_example(seven.value().text, "ahoge.json", "girl/ahoge", some_view({1.0f, 1.0f, -1.0f}));
    ASSERT_FALSE(eight.ok());
    EXPECT_NE(eight.error().message.find("already has 7 view examples"), std::string::npos) << eight.error().message;
    // Near an existing one it still works: it replaces.
    auto near = add_view_example(seven.value().text, "ahoge.json", "girl/ahoge", some_view({0.0f, 0.1f, -1.0f}));
    ASSERT_TRUE(near.ok()) << near.error().message;
    EXPECT_EQ(near.value().replaced_name, "back");
}

// What the loader would refuse is refused before it reaches the text, naming the file, the
// chain and the value (fuzz_scene_edit found a negative influence written back).
TEST(SketchSave, RefusesAViewTheLoaderWouldNotTake) {
    const std::string text = testing_support::file_bytes(ahoge_path());
    const auto refused = [&](ViewSpec view, const std::string& expected) {
        auto edit = add_view_example(text, "ahoge.json", "girl/ahoge", view);
        ASSERT_FALSE(edit.ok()) << expected;
        EXPECT_NE(edit.error().message.find("ahoge.json: the sketch for chain \"girl/ahoge\": " + expected), std::string::npos)
            << edit.error().message;
    };
    ViewSpec v = some_view({1.0f, 0.0f, 0.0f});
    v.view.influence = -4.19f;
    refused(v, "influence: expected a number in (0, 1000], got -4.19");
    v.view.influence = 1001.0f;
    refused(v, "influence: expected a number in (0, 1000], got 1001");
    v.view.influence = std::numeric_limits<float>::quiet_NaN();
    refused(v, "influence: expected a number in (0, 1000], got nan");
    v = some_view({1.0f, 0.0f, 0.0f});
    v.view.direction = glm::vec3(0.0f);
    refused(v, "direction: expected a finite non-zero vector, got [0, 0, 0]");
    v = some_view({1.0f, 0.0f, 0.0f});
    v.shape.positions[5].y = 1e3f;
    refused(v, "shape joint 5: expected coordinates in [-100, 100] m");
    v = some_view({1.0f, 0.0f, 0.0f});
    v.shape.positions[3] = v.shape.positions[2];
    refused(v, "shape joint 3: expected a point at least 1e-6 m from the previous joint");
    v = some_view({1.0f, 0.0f, 0.0f});
    v.shape.orientations[4] = glm::quat(0.0f, 0.0f, 0.0f, 0.0f);
    refused(v, "shape joint 4: expected a non-zero finite orientation quaternion");
    // The bounds themselves are taken, and load back.
    v = some_view({1.0f, 0.0f, 0.0f});
    v.view.influence = 1000.0f;
    auto edit = add_view_example(text, "ahoge.json", "girl/ahoge", v);
    ASSERT_TRUE(edit.ok()) << edit.error().message;
    EXPECT_TRUE(parse_scene(edit.value().text, "ahoge.json").ok());
}

TEST(SketchSave, WritesOnlyAValidScene) {
    const testing_support::TempDir dir;
    const std::string path = dir.file("scene.json");
    const std::string text = testing_support::file_bytes(ahoge_path());
    auto edit = add_view_example(text, path, "girl/ahoge", some_view({1.0f, 1.0f, 1.0f}));
    ASSERT_TRUE(edit.ok());
    ASSERT_TRUE(write_scene_text(path, edit.value().text).ok());
    EXPECT_EQ(testing_support::file_bytes(path), edit.value().text);
    auto loaded = load_scene(path);
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    EXPECT_EQ(ahoge_chain(loaded.value()).views.size(), 6u);

    // A text that does not load is not written, and the old file stays.
    std::string broken = edit.value().text;
    broken.replace(broken.find("\"influence\": 7.5"), 16, "\"influence\": -1 ");
    auto refused = write_scene_text(path, broken);
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.error().message.find("nothing was written"), std::string::npos) << refused.error().message;
    EXPECT_EQ(testing_support::file_bytes(path), edit.value().text);
    EXPECT_EQ(dir.entries().size(), 1u);  // no temporary file left
}

// A scene written to another folder names its files from there (docs/sketch.md, --out):
// relative paths are rewritten, absolute ones and URLs kept, the rest of the text kept.
TEST(SketchSave, AMovedSceneNamesTheSameFiles) {
    const std::string text = R"({
  "$schema": "../docs/scene.schema.json",
  "name": "moved",
  "flocks": [{"model": "birds/crow.glb", "map": "/abs/map.json"}, {"wing_type": "small"}],
  "characters": [{"name": "a", "gltf": "characters/a.vrm",
                  "motions": [{"name": "m", "file": "motions/m.vrma", "map": "maps/m.json", "target_map": "maps/t.json"}]},
                 {"name": "b", "shape": "characters/not-a-file-member.glb"}]
}
)";
    auto down = move_scene_text(text, "/p/scenes/a.json", "/p/scenes/out/b.json");
    ASSERT_TRUE(down.ok()) << down.error().message;
    const Json moved = Json::parse(down.value());
    EXPECT_EQ(moved["$schema"], "../../docs/scene.schema.json");
    EXPECT_EQ(moved["flocks"][0]["model"], "../birds/crow.glb");
    EXPECT_EQ(moved["flocks"][0]["map"], "/abs/map.json");
    EXPECT_EQ(moved["characters"][0]["gltf"], "../characters/a.vrm");
    EXPECT_EQ(moved["characters"][0]["motions"][0]["file"], "../motions/m.vrma");
    EXPECT_EQ(moved["characters"][0]["motions"][0]["map"], "../maps/m.json");
    EXPECT_EQ(moved["characters"][0]["motions"][0]["target_map"], "../maps/t.json");
    // A member that names no file keeps its text.
    EXPECT_EQ(moved["characters"][1]["shape"], "characters/not-a-file-member.glb");
    // Only the paths' strings change: with them put back the text is the original's.
    std::string back = down.value();
    for (const auto& [now, was] : std::vector<std::pair<std::string, std::string>>{
             {"../../docs/scene.schema.json", "../docs/scene.schema.json"}, {"../birds/crow.glb", "birds/crow.glb"},
             {"../characters/a.vrm", "characters/a.vrm"}, {"../motions/m.vrma", "motions/m.vrma"}, {"../maps/m.json", "maps/m.json"},
             {"../maps/t.json", "maps/t.json"}}) {
        back.replace(back.find(now), now.size(), was);
    }
    EXPECT_EQ(back, text);

    auto up = move_scene_text(text, "/p/scenes/a.json", "/p/b.json");
    ASSERT_TRUE(up.ok());
    EXPECT_EQ(Json::parse(up.value())["characters"][0]["gltf"], "scenes/characters/a.vrm");
    auto same = move_scene_text(text, "/p/scenes/a.json", "/p/scenes/./c.json");
    ASSERT_TRUE(same.ok());
    EXPECT_EQ(same.value(), text);
    EXPECT_FALSE(move_scene_text("{\"name\": ", "bad.json", "/p/c.json").ok());
    // $schema is a URI reference: one with a scheme names no file of the scene's folder.
    const std::string url = R"({"$schema": "https://example.org/scene.schema.json", "name": "u"})";
    auto kept = move_scene_text(url, "/p/scenes/a.json", "/p/b.json");
    ASSERT_TRUE(kept.ok());
    EXPECT_EQ(kept.value(), url);

    // A shipped scene with a model and motions, moved to a temporary folder, loads there
    // and reads the same files.
    const std::string avatars = std::string(KODAWARI_SOURCE_DIR) + "/scenes/avatars.json";
    const testing_support::TempDir dir;
    auto original = load_scene(avatars);
    ASSERT_TRUE(original.ok()) << original.error().message;
    auto copy = move_scene_text(testing_support::file_bytes(avatars), avatars, dir.file("avatars.json"));
    ASSERT_TRUE(copy.ok());
    auto reparsed = parse_scene(copy.value(), dir.file("avatars.json"));
    ASSERT_TRUE(reparsed.ok()) << reparsed.error().message;
    ASSERT_EQ(reparsed.value().inputs.size(), original.value().inputs.size());
    ASSERT_GT(original.value().inputs.size(), 2u);
    for (std::size_t i = 0; i < original.value().inputs.size(); ++i) {
        EXPECT_TRUE(same_file(reparsed.value().inputs[i].path, original.value().inputs[i].path))
            << reparsed.value().inputs[i].path << " vs " << original.value().inputs[i].path;
    }
}

// A scene is never written over a file it reads (`sketch chibi.json --out chibi.glb`).
TEST(SketchSave, NeverOverAFileTheSceneReads) {
    const testing_support::TempDir dir;
    const std::string model = dir.file("chibi.glb");
    const std::string bytes = testing_support::file_bytes(std::string(KODAWARI_SOURCE_DIR) + "/scenes/characters/chibi.glb");
    {
        std::ofstream out(model, std::ios::binary);
        out << bytes;
    }
    const std::string text = R"({"format": "kodawari-scene", "version": 2, "name": "c",
 "characters": [{"name": "chibi", "gltf": "chibi.glb", "chains": [{"name": "ahoge_0", "root": "ahoge_0"}]}]})";
    ASSERT_TRUE(write_scene_text(dir.file("chibi.json"), text).ok());
    auto refused = write_scene_text(model, text);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(refused.error().message.find("is the model of character \"chibi\", which the scene reads"), std::string::npos)
        << refused.error().message;
    EXPECT_EQ(testing_support::file_bytes(model), bytes);
    EXPECT_EQ(dir.entries().size(), 2u);  // the model and the scene: no temporary file left
}

TEST(SketchSave, StrokeFiles) {
    auto good = parse_stroke(R"({"points": [[1, 2], [3.5, -4e1]]})", "s.json");
    ASSERT_TRUE(good.ok()) << good.error().message;
    ASSERT_EQ(good.value().size(), 2u);
    EXPECT_EQ(good.value()[1], glm::dvec2(3.5, -40.0));
    const auto message = [](const std::string& text) {
        auto r = parse_stroke(text, "s.json");
        return r.ok() ? std::string("ok") : r.error().message;
    };
    EXPECT_NE(message(R"({"points": [[1, 2]]})").find("s.json: $.points: expected an array of at least 2"), std::string::npos);
    EXPECT_NE(message(R"({"points": [[1, 2], [3, "4"]]})").find("s.json: $.points[1][1]: expected a finite number"),
              std::string::npos);
    // Overflow to infinity: refused, whether by the JSON parser or the finiteness check.
    EXPECT_EQ(message(R"({"points": [[1, 2], [3, 1e999]]})").find("s.json: "), 0u);
    EXPECT_NE(message(R"({"points": [[1, 2], [3]]})").find("$.points[1]: expected a point [x, y]"), std::string::npos);
    EXPECT_NE(message(R"({"pts": []})").find("$.pts: unknown key"), std::string::npos);
    EXPECT_NE(message(R"({"points": )").find("s.json: not valid JSON"), std::string::npos);
}

}  // namespace
}  // namespace kodawari
