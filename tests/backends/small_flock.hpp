#pragma once
// A flock of hawks on one route (37 by default: not a multiple of any workgroup size),
// built from a scene as an application builds one: for the tests of the vulkan birds'
// recording and layouts.
#include <gtest/gtest.h>

#include <string>

#include "kodawari/scene/scene.hpp"

namespace kodawari::testing_support {

inline birds::BirdWorld small_flock(unsigned count = 37) {
    auto scene = parse_scene(R"({"format": "kodawari-scene", "version": 1, "name": "record", "fps": 60, "duration": 1,
        "flocks": [{"name": "f", "wing_type": "hawk", "count": )" +
                                 std::to_string(count) + R"(,
                    "route": {"points": [[0, 10, 0], [10, 20, 0], [30, 0, 10], [40, 10, 0]]}}]})",
                             "(test)");
    EXPECT_TRUE(scene.ok()) << scene.error().message;
    auto world = build_bird_world(scene.value());
    EXPECT_TRUE(world.ok()) << world.error().message;
    return std::move(world).value();
}

}  // namespace kodawari::testing_support
