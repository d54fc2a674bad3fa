/* Preloaded (LD_PRELOAD) by `make asan`: keeps the Vulkan driver (lavapipe) and the
 * Khronos validation layer mapped after the Vulkan loader closes them, so that
 * LeakSanitizer names their frames (and tests/lsan.supp suppresses the layer's own
 * allocations) instead of reporting leaks from "<unknown module>". RTLD_LOCAL puts none of
 * their symbols in the global scope (the layer exports vkGetInstanceProcAddr), so nothing
 * the application or the loader calls is interposed; the loader's own dlopen() of the same
 * files gets these objects, and RTLD_NODELETE keeps them past its dlclose().
 * Built without sanitizers, and preloaded into every process of the tests (bash, node,
 * python, Blender): only a process with the sanitizers' runtime (ours) loads the two, as
 * loading them cost every other process 0.1 s (bash) to 7 s (python3) on this machine
 * (CI stop 49: the asan lane's scripts and generators). */
#include <dlfcn.h>

__attribute__((constructor)) static void kodawari_keep_loaded(void) {
    if (dlsym(RTLD_DEFAULT, "__asan_init") == 0) return;
    (void)dlopen("libvulkan_lvp.so", RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    (void)dlopen("libVkLayer_khronos_validation.so", RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
}
