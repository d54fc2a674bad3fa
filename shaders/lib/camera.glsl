// The camera quantities of the layers drawn from device buffers (chains.vert,
// colliders.vert, birds.vert), computed as the CPU draw lists compute them
// (engine/render/renderer.cpp, scene_draw.cpp), so a layer and the draw list it replaces
// agree on sizes and orientation.
#ifndef KODAWARI_SHADERS_LIB_CAMERA_GLSL
#define KODAWARI_SHADERS_LIB_CAMERA_GLSL

#include "shared/render.h"

// The world size of one pixel at the depth of p; 0 at or behind the near plane
// (orthographic: the same everywhere).
float pixel_size_at(RenderPush camera, vec3 p) {
    if (camera.draw.w == KW_RENDER_ORTHOGRAPHIC) return camera.forward.w;
    float depth = dot(p - camera.eye.xyz, camera.forward.xyz);
    return depth > camera.eye.w ? depth * camera.forward.w : 0.0;
}

// render::camera_basis(): right and up of a view along unit `forward`, world up +y
// (+z when looking nearly straight up or down).
void camera_basis(vec3 forward, out vec3 right, out vec3 up) {
    vec3 world_up = abs(forward.y) > 0.999 ? vec3(0.0, 0.0, 1.0) : vec3(0.0, 1.0, 0.0);
    right = normalize(cross(forward, world_up));
    up = cross(right, forward);
}

#endif
