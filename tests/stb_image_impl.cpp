// stb_image's implementation (Debian's libstb-dev header) for the tests that reload PNG
// files, compiled without the project's warnings (tests/CMakeLists.txt).
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>
