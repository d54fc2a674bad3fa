#pragma once
// KODAWARI_INTERNAL: the internal functions and classes (engine/<folder>/*.hpp, never
// installed) that one component calls in another, or that the white-box tests call: the
// compute layer and gpu/ (kodawari::vulkan) used by the renderer, core/ and the birds'
// meshes (kodawari::sim) used by vulkan, io and render. A shared build makes each
// component a library of its own, compiled with hidden visibility, so these are exported
// as KODAWARI_API is. They are not part of the API: no installed header declares them,
// and they change in any release.

#include "kodawari/core/api.hpp"

#define KODAWARI_INTERNAL KODAWARI_API
