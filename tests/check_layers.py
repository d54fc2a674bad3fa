#!/usr/bin/env python3
"""Layering of the engine's component targets (engine/CMakeLists.txt, issue 19), and the
layers that must name no domain (NEUTRAL, issue 31).

No target's sources include, directly or through other headers, a header of a target it
does not link, or a third-party header it does not link. Which target owns a header is
derived from engine/CMakeLists.txt, not listed here (issue 31, item 4): an engine folder
is one component (all of its sources compiled into one kodawari_component(); its internal
headers are that component's), and a public header is the component's whose
kodawari_headers() installs it, every header of one public folder (include/kodawari/<f>/)
the same component's. So a new folder or header needs no entry here, and a folder whose
files go to two components is reported. The link test (tests/consumers/sim_only.cpp)
cannot see header-only libraries such as nlohmann-json; this can.

Every header under include/kodawari/ is installed once (kodawari_headers()), so that a
new public header is installed and an internal one is not. Generated headers (api.hpp,
version.hpp) are their .in templates here.

Usage: check_layers.py SOURCE_DIR
"""
import os
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
    # types) for kodawari/vulkan/vulkan_embed.hpp; kodawari.h itself names no Vulkan type.
    "c": {"vulkan"},
}
# Which target owns each header is derived, never listed by hand (issue 31, item 4): an
# engine folder is one component (every source in it is compiled into the same
# kodawari_component(), and its internal headers belong to that component), and a public
# header belongs to the component whose kodawari_headers() installs it, every header of a
# public subfolder (include/kodawari/<folder>/) to the same one.
INTERNAL_HEADERS = ("*.hpp", "*.h")


def generated(path):
    """A generated header's name: its template's without .in."""
    return path[: -len(".in")] if path.endswith(".in") else path


def folder_components(found):
    """Each engine folder's component, from the components' sources; a folder whose
    sources go to two components is a problem."""
    folders, problems = {}, []
    for target, sources in found.items():
        for source in sources:
            folder = str(pathlib.PurePosixPath(source).parent)
            folders.setdefault(folder, set()).add(target)
    for folder, targets_of in sorted(folders.items()):
        if len(targets_of) > 1:
            problems.append(f"engine/{folder}/: sources of {' and '.join(sorted(targets_of))} "
                            "(a folder is one component: move one side's files to a folder of its own)")
    return {folder: sorted(t)[0] for folder, t in folders.items()}, problems


def owners(found):
    """Every engine header's owning component, and the problems of deriving it."""
    folder_of, problems = folder_components(found)
    table = {}
    for folder, target in folder_of.items():
        for pattern in INTERNAL_HEADERS:
            for path in (ENGINE / folder).glob(pattern):
                table[str(path.relative_to(ENGINE))] = target
    subfolder_owner = {}
    for target, headers in installed_headers().items():
        for header in headers:
            table[header] = target
            parts = pathlib.PurePosixPath(header).parts  # include, kodawari, [folder,] name
            if len(parts) > 3:
                first = subfolder_owner.setdefault(parts[2], (target, header))
                if first[0] != target:
                    problems.append(f"{header}: installed by {target}, but {first[1]} of the same folder by {first[0]} "
                                    "(a public folder is one component)")
    return table, problems


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


def public_headers():
    """Every header file under include/kodawari/ (generated ones by their installed name)."""
    found = set()
    # os.walk follows include/kodawari/shared, a link to shaders/shared (rglob would not).
    for folder, _, files in os.walk(ENGINE / "include/kodawari", followlinks=True):
        for name in files:
            if name.endswith((".hpp", ".h", ".hpp.in")):
                path = pathlib.Path(folder) / name
                found.add(generated(str(path.relative_to(ENGINE))))
    return found


def check_installed():
    """Every public header installed once; nothing else installed."""
    problems = []
    listed = {}
    public = public_headers()
    for target, headers in installed_headers().items():
        for header in headers:
            if header in listed:
                problems.append(f"{header}: installed by both {listed[header]} and {target}")
            listed[header] = target
            if header not in public:
                problems.append(f"{header}: installed by {target} but not a public header")
    for header in sorted(public - set(listed)):
        problems.append(f"{header}: a public header that kodawari_headers() does not install")
    # One folder per component (issue 31, item 4): the top level holds the C API's header
    # alone; the forwarding headers of the old top-level paths are generated at install.
    for header in sorted(public):
        if header.count("/") == 2 and header != "include/kodawari/kodawari.h":
            problems.append(f"{header}: a public header outside a component's folder "
                            "(include/kodawari/<component>/)")
    return problems, len(listed)


# The layers that know domains only through the domain contract (issue 31): no code in
# them (comments aside) names a domain. gpu/ (Vulkan's instance, device and graphics) is
# not in the list: shared_layout.cpp checks every shared struct's layout, domains' too.
NEUTRAL = ["simulation/*.cpp", "simulation/*.hpp", "include/kodawari/simulation/simulation.hpp", "include/kodawari/simulation/bake.hpp",
           "include/kodawari/simulation/domain.hpp", "include/kodawari/backends/device_data.hpp", "include/kodawari/simulation/shards.hpp", "include/kodawari/simulation/distributed.hpp",
           # The renderer and its shared layout: domains draw through render::Draw and
           # their own render layers (render/layer.hpp).
           "render/*.cpp", "render/*.hpp", "include/kodawari/render/*.hpp", "include/kodawari/shared/render.h",
           # The compute layer: its interface and its Vulkan implementation.
           "include/kodawari/vulkan/compute.hpp", "gpu/compute_*.cpp", "gpu/compute_vulkan.hpp"]
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
# Vulkan handles come in through kodawari/vulkan/vulkan_embed.hpp alone.
VULKAN_FREE = ["include/kodawari/vulkan/compute.hpp", "include/kodawari/backends/backend.hpp", "include/kodawari/backends/device_data.hpp",
               "include/kodawari/vulkan/backend_factory.hpp", "include/kodawari/vulkan/gpu_info.hpp"]
VULKAN_WORDS = re.compile(r"\bvk::|\bVk[A-Z]\w*|\bVK_\w+|(?<!kodawari/)vulkan[/_]\w+\.h|gpu::VulkanContext")


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
    found = targets()
    owner, derived = owners(found)
    problems = derived + check_neutral() + check_vulkan_free()

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
                problems.append(f"{header}: no owner (neither in a component's folder nor installed by one)")
                continue
            if owner[header] not in LINKS[target]:
                problems.append(f"{target}: {source} includes {include} ({owner[header]})")
            scan(source_file(header), target, seen)

    for target, sources in found.items():
        for source in sources:
            if source.endswith(".cpp"):
                scan(ENGINE / source, target, set())
    installed, count = check_installed()
    problems += installed
    for line in problems:
        print(line)
    print("checked", {t: len(s) for t, s in found.items()}, "installed headers", count, "problems", len(problems))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(check())
