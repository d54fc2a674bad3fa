/* Preloaded (LD_PRELOAD) by `make asan`: keeps the Vulkan driver (lavapipe) and the
 * Khronos validation layer mapped after the Vulkan loader closes them, so that
 * LeakSanitizer names their frames (and tests/lsan.supp suppresses the layer's own
 * allocations) instead of reporting leaks from "<unknown module>". RTLD_LOCAL puts none of
 * their symbols in the global scope (the layer exports vkGetInstanceProcAddr), so nothing
 * the application or the loader calls is interposed; the loader's own dlopen() of the same
 * files gets these objects, and RTLD_NODELETE keeps them past its dlclose(). Built without
 * sanitizers: it is preloaded into every process of the tests (bash, node, python). */
#include <dlfcn.h>

__attribute__((constructor)) static void kodawari_keep_loaded(void) {
    (void)dlopen("libvulkan_lvp.so", RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    (void)dlopen("libVkLayer_khronos_validation.so", RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
}
