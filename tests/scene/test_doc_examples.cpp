// The scenes docs/scene-format.md shows whole (its ```json blocks with "format":
// "kodawari-scene"): each one a reader copies loads, passes the route check that
// `--strict` turns into errors, and simulates. The version 1 example had come to fly
// its gulls up a 21-degree climb (the gull's limit is 14.8) and its pigeons round turns
// of 6.8 m (their least is 22.8 m at their speed): 11 warnings on the first paste.

#include <cstddef>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "kodawari/scene/route_check.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "test_paths.hpp"

using namespace kodawari;

namespace {

// The text of every ```json block of `markdown` that is a whole scene.
std::vector<std::string> scene_blocks(const std::string& markdown) {
    std::vector<std::string> out;
    const std::string open = "```json\n";
    for (std::size_t at = markdown.find(open); at != std::string::npos; at = markdown.find(open, at)) {
        const std::size_t begin = at + open.size();
        const std::size_t end = markdown.find("```", begin);
        if (end == std::string::npos) break;
        std::string block = markdown.substr(begin, end - begin);
        if (block.find("\"format\": \"kodawari-scene\"") != std::string::npos) out.push_back(std::move(block));
        at = end + 3;
    }
    return out;
}

TEST(DocExamples, TheSceneFormatsWholeScenesLoadPassTheRouteCheckAndSimulate) {
    const std::string path = std::string(KODAWARI_SOURCE_DIR) + "/docs/scene-format.md";
    std::ifstream in(path);
    ASSERT_TRUE(in) << path;
    std::stringstream text;
    text << in.rdbuf();
    const std::vector<std::string> blocks = scene_blocks(text.str());
    // The tower's flocking flock, the version 1 flocks, the version 2 character.
    ASSERT_EQ(blocks.size(), 3u);
    for (std::size_t k = 0; k < blocks.size(); ++k) {
        const std::string name = "docs/scene-format.md example " + std::to_string(k);
        SCOPED_TRACE(name);
        auto scene = parse_scene(blocks[k], name);
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        auto warnings = check_routes(scene.value());
        ASSERT_TRUE(warnings.ok()) << warnings.error().message;
        for (const RouteWarning& w : warnings.value()) ADD_FAILURE() << w.message;
        auto sim = Simulation::create(std::move(scene).value(), {.backend = BackendKind::Cpu, .options = {}, .frames = 3});
        ASSERT_TRUE(sim.ok()) << sim.error().message;
        EXPECT_TRUE(sim.value()->step(3).ok());
    }
}

}  // namespace
