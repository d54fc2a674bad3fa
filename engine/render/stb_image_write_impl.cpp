// stb_image_write's implementation (Debian's libstb-dev header), compiled once here
// without the project's warnings (engine/CMakeLists.txt): it is third-party code.
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb/stb_image_write.h>

namespace kodawari::render {

/// PNG bytes of an RGBA8 image through `write` (engine/render/image.cpp).
int stb_png_to_func(stbi_write_func* write, void* context, int width, int height, const void* rgba) {
    return stbi_write_png_to_func(write, context, width, height, 4, rgba, width * 4);
}

}  // namespace kodawari::render
