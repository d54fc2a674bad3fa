#!/usr/bin/env python3
"""Layering of the engine's component targets (engine/CMakeLists.txt, issue 19), and the
layers that must name no domain (NEUTRAL, issue 31).

No target's sources include, directly or through other headers, a header of a target it
does not link, or a third-party header it does not link. A header belongs to the target
that defines what it declares (OWNERS below); a new header needs an entry, so that its
layer is a decision. The link test (tests/consumers/sim_only.cpp) cannot see header-only
libraries such as nlohmann-json; this can.

The public headers are also what `cmake --install` copies (kodawari_headers() in
engine/CMakeLists.txt): every header under include/kodawari/ is listed there once, under
the target that owns it, so that a new public header is installed and an internal one is
not. Generated headers (api.hpp, version.hpp) are their .in templates here.

Usage: check_layers.py SOURCE_DIR
"""
import pathlib
import re
import sys

ENGINE = (pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".") / "engine").resolve()

# What each target links (itself included), as engine/CMakeLists.txt says.
LINKS = {
    "sim": {"sim"},
    "vulkan": {"vulkan", "sim"},
    "io": {"io", "sim"},
    "render": {"render", "vulkan", "io", "sim"},
    "engine": {"engine", "render", "vulkan", "io", "sim"},
    # The scene simulations (capi/capi_simulation.cpp) open Simulation and bake.
    "c": {"c", "engine", "render", "vulkan", "io", "sim"},
}
# The third-party headers each target may include (prefixes of the include path).
THIRD_PARTY = {"tiny_gltf", "nlohmann", "vulkan/", "stb/", "hwy/"}
ALLOWED_THIRD_PARTY = {
    "sim": {"hwy"},
    "vulkan": {"vulkan"},
    "io": {"tiny_gltf", "nlohmann"},
    "render": {"vulkan", "stb"},
    # Part files' JSON header (simulation/shards.cpp); the flocking cpu backend's
    # hand-tuned search (domains/flocking/flock_search_simd.cpp, with simd/dispatch.hpp).
    "engine": {"vulkan", "nlohmann", "hwy"},
    # The C API's device embedding converts the application's handles (vulkan_core.h's C
    # types) for kodawari/vulkan_embed.hpp; kodawari.h itself names no Vulkan type.
    "c": {"vulkan"},
}
# Which target owns each header: folders first, then the public headers one by one.
OWNER_PATTERNS = [
    ("include/kodawari/*.hpp", "sim"),
    ("include/kodawari/*.hpp.in", "sim"),
    ("include/kodawari/shared/*.h", "sim"),
    ("include/kodawari/birds/*.hpp", "sim"),
    ("include/kodawari/rods/*.hpp", "sim"),
    ("core/*.hpp", "sim"),
    ("birds/*.hpp", "sim"),
    ("backends/backends.hpp", "sim"),
    ("backends/pose_backends.hpp", "sim"),
    ("simd/*.hpp", "sim"),
    ("simd/*-inl.h", "sim"),
    ("backends/device_backends.hpp", "vulkan"),
    ("gpu/*.hpp", "vulkan"),
    ("scene/*.hpp", "io"),
    ("export/*.hpp", "io"),
    ("gltf/*.hpp", "io"),
    ("render/*.hpp", "render"),
    ("include/kodawari/render/*.hpp", "render"),
    ("capi/*.hpp", "c"),
    ("simulation/*.hpp", "engine"),
    ("domains/*.hpp", "engine"),
    ("domains/flocking/*.hpp", "engine"),
]
PUBLIC_OWNERS = {
    "gltf/character.hpp": "sim",
    "gltf/pose_instance.hpp": "sim",
    "gltf/chains.hpp": "io",
    "gltf/vrm.hpp": "io",
    "gltf/motion.hpp": "io",
    "gltf/rig_scene.hpp": "io",
    "gltf/import.hpp": "io",
    "gltf/bird_model_import.hpp": "io",
    "route_check.hpp": "io",
    "compute.hpp": "vulkan",
    "backend_factory.hpp": "vulkan",
    "crowd_animator.hpp": "vulkan",
    "vulkan_embed.hpp": "vulkan",
    "gpu_info.hpp": "vulkan",
    "scene.hpp": "io",
    "export.hpp": "io",
    "scene_edit.hpp": "io",
    "sketch_key.hpp": "io",
    "simulation.hpp": "engine",
    "domain.hpp": "engine",
    "domains/birds.hpp": "engine",
    "domains/chains.hpp": "engine",
    "domains/chain_draw.hpp": "engine",
    "domains/bird_draw.hpp": "engine",
    "domains/scene_draw.hpp": "engine",
    "domains/flocking.hpp": "engine",
    "domains/trace.hpp": "engine",
    "bake.hpp": "engine",
    "shards.hpp": "engine",
    "distributed.hpp": "engine",
    "kodawari.h": "c",
}


def generated(path):
    """A generated header's name: its template's without .in."""
    return path[: -len(".in")] if path.endswith(".in") else path


def owners():
    table = {}
    for pattern, target in OWNER_PATTERNS:
        for path in ENGINE.glob(pattern):
            table[generated(str(path.relative_to(ENGINE)))] = target
    for header, target in PUBLIC_OWNERS.items():
        table["include/kodawari/" + header] = target
    return table


def targets():
    """Each target's sources, from the kodawari_component() calls and the C API's shared
    library (add_library(kodawari_c SHARED ...))."""
    text = (ENGINE / "CMakeLists.txt").read_text()
    found = {m.group(1): m.group(2).split() for m in re.finditer(r"kodawari_component\((\w+)\n(.*?)\)", text, re.S)}
    for m in re.finditer(r"add_library\(kodawari_(\w+) SHARED\n(.*?)\)", text, re.S):
        found[m.group(1)] = m.group(2).split()
    return found


def resolve(include, source):
    """The engine header an include names (relative to engine/), or None outside the engine."""
    for base in (ENGINE / "include", ENGINE, source.parent):
        path = (base / include).resolve()
        if path.exists() or path.with_name(path.name + ".in").exists():
            return str(path.relative_to(ENGINE)) if str(path).startswith(str(ENGINE)) else None
    return None


def source_file(header):
    """The file to read for an engine header: the header, or its template."""
    path = ENGINE / header
    return path if path.exists() else path.with_name(path.name + ".in")


def installed_headers():
    """Each target's public headers, from the kodawari_headers() calls (under include/)."""
    text = (ENGINE / "CMakeLists.txt").read_text()
    return {m.group(1): ["include/kodawari/" + h for h in m.group(2).split()]
            for m in re.finditer(r"kodawari_headers\((\w+)\n(.*?)\)", text, re.S)}


def check_installed(owner):
    """Every public header installed once, by its owner; nothing else installed."""
    problems = []
    listed = {}
    for target, headers in installed_headers().items():
        for header in headers:
            if header in listed:
                problems.append(f"{header}: installed by both {listed[header]} and {target}")
            listed[header] = target
            if header not in owner or not header.startswith("include/"):
                problems.append(f"{header}: installed by {target} but not a public header")
            elif owner[header] != target:
                problems.append(f"{header}: installed by {target}, owned by {owner[header]}")
    for header in sorted(h for h in owner if h.startswith("include/")):
        if header not in listed:
            problems.append(f"{header}: a public header that kodawari_headers() does not install")
    return problems, len(listed)


# The layers that know domains only through the domain contract (issue 31): no code in
# them (comments aside) names a domain. gpu/ (Vulkan's instance, device and graphics) is
# not in the list: shared_layout.cpp checks every shared struct's layout, domains' too.
NEUTRAL = ["simulation/*.cpp", "simulation/*.hpp", "include/kodawari/simulation.hpp", "include/kodawari/bake.hpp",
           "include/kodawari/domain.hpp", "include/kodawari/device_data.hpp", "include/kodawari/shards.hpp", "include/kodawari/distributed.hpp",
           # The renderer and its shared layout: domains draw through render::Draw and
           # their own render layers (render/layer.hpp).
           "render/*.cpp", "render/*.hpp", "include/kodawari/render/*.hpp", "include/kodawari/shared/render.h",
           # The compute layer: its interface and its Vulkan implementation.
           "include/kodawari/compute.hpp", "gpu/compute_*.cpp", "gpu/compute_vulkan.hpp"]
# Inside identifiers too (set_chains, RodBackend, birds_from); "produce" is not a rod, a
# swapchain is not a chain.
DOMAIN_WORDS = re.compile(r"bird|rod(?!uc)|(?<!swap)chain|flock", re.I)


def code_of(text):
    """`text` without its comments and string literals' contents."""
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r"//[^\n]*", "", text)
    return re.sub(r'"(?:\\.|[^"\\])*"', '""', text)


def check_neutral():
    """Identifiers naming a domain in the neutral layers, as `file:line: word`."""
    problems = []
    for pattern in NEUTRAL:
        for path in sorted(ENGINE.glob(pattern)):
            for number, line in enumerate(code_of(path.read_text()).splitlines(), 1):
                for m in DOMAIN_WORDS.finditer(line):
                    problems.append(f"{path.relative_to(ENGINE)}:{number}: names a domain ({m.group(0)}): {line.strip()}")
    return problems


# The compute layer's interface and what a domain or an embedder reaches it through name no
# Vulkan type (issue 31, item 2): Vulkan is its implementation, in gpu/; the application's
# Vulkan handles come in through kodawari/vulkan_embed.hpp alone.
VULKAN_FREE = ["include/kodawari/compute.hpp", "include/kodawari/backend.hpp", "include/kodawari/device_data.hpp",
               "include/kodawari/backend_factory.hpp", "include/kodawari/gpu_info.hpp"]
VULKAN_WORDS = re.compile(r"\bvk::|\bVk[A-Z]\w*|\bVK_\w+|vulkan[/_]\w+\.h|gpu::VulkanContext")


def check_vulkan_free():
    """Vulkan types (or includes) in the headers of VULKAN_FREE, as `file:line: word`."""
    problems = []
    for header in VULKAN_FREE:
        path = ENGINE / header
        text = re.sub(r"//[^\n]*", "", path.read_text())  # comments may name Vulkan
        for number, line in enumerate(text.splitlines(), 1):
            for m in VULKAN_WORDS.finditer(line):
                problems.append(f"{header}:{number}: names Vulkan ({m.group(0)}): {line.strip()}")
    return problems


def check():
    owner = owners()
    problems = check_neutral() + check_vulkan_free()

    def scan(source, target, seen):
        if source in seen:
            return
        seen.add(source)
        for include in re.findall(r'#include\s*[<"]([^>"]+)[>"]', source.read_text()):
            if include.startswith(tuple(THIRD_PARTY)):
                if not include.startswith(tuple(ALLOWED_THIRD_PARTY[target])):
                    problems.append(f"{target}: {source} includes {include}")
                continue
            if include.startswith("kodawari/shared/"):
                continue  # the GPU-shared structs: plain data, every layer may use them
            header = resolve(include, source)
            if header is None:
                continue  # the standard library, glm
            if header not in owner:
                problems.append(f"{header}: no owner in check_layers.py")
                continue
            if owner[header] not in LINKS[target]:
                problems.append(f"{target}: {source} includes {include} ({owner[header]})")
            scan(source_file(header), target, seen)

    found = targets()
    for target, sources in found.items():
        for source in sources:
            if source.endswith(".cpp"):
                scan(ENGINE / source, target, set())
    installed, count = check_installed(owner)
    problems += installed
    for line in problems:
        print(line)
    print("checked", {t: len(s) for t, s in found.items()}, "installed headers", count, "problems", len(problems))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(check())
