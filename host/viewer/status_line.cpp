// The viewer's status line, drawn as overlay triangles in stb_easy_font's pixel font.
#include <cstring>
#include <vector>

#include <stb/stb_easy_font.h>

#include "viewer.hpp"

namespace kodawari::cli {

namespace {
constexpr render::Rgba8 kTextColor{255, 255, 255};
constexpr render::Rgba8 kTextBackColor{20, 24, 32};
}  // namespace

void add_status(render::DrawList& list, const std::string& line) {
    static std::vector<char> buffer(1 << 16);
    const float scale = list.width() >= 1200 ? 2.0f : 1.0f;
    const int quads = stb_easy_font_print(0.0f, 0.0f, const_cast<char*>(line.c_str()), nullptr, buffer.data(),
                                          static_cast<int>(buffer.size()));
    const float band = 14.0f * scale;
    const float w = static_cast<float>(list.width()), h = static_cast<float>(list.height());
    const glm::vec2 origin{4.0f * scale, h - band + 3.0f * scale};
    for (int q = 0; q < quads; ++q) {
        glm::vec2 p[4];
        for (int i = 0; i < 4; ++i) {
            float xy[2];
            std::memcpy(xy, buffer.data() + (q * 4 + i) * 16, sizeof(xy));
            p[i] = origin + scale * glm::vec2(xy[0], xy[1]);
        }
        list.add_screen_triangle(p[0], p[1], p[2], kTextColor);
        list.add_screen_triangle(p[0], p[2], p[3], kTextColor);
    }
    // The band after the glyphs: overlays share depth 0 and the depth test is "less", so
    // the first drawn wins.
    list.add_screen_triangle({0.0f, h - band}, {w, h - band}, {w, h}, kTextBackColor);
    list.add_screen_triangle({0.0f, h - band}, {w, h}, {0.0f, h}, kTextBackColor);
}

}  // namespace kodawari::cli
