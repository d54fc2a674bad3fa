// The C API's chain setup (issue 33): `kodawari rig` for a character file, what the
// Blender add-on's bake_chains calls on the armature it exported. gltf::make_rig_scene
// writes the scene's text; it is checked by the scene loader and written atomically, as
// the command does (host/cmd_rig.cpp).
#include <string>

#include "capi/capi_common.hpp"
#include "kodawari/core/atomic_file.hpp"
#include "kodawari/gltf/rig_scene.hpp"
#include "kodawari/scene/scene.hpp"

using namespace kodawari;
using namespace kodawari::capi;

extern "C" {

KODAWARI_C_API kodawari_status kodawari_rig_scene(const char* character_path, const char* scene_path, const char* clip,
                                                  float duration, char* chains, size_t chains_size) {
    return guard("kodawari_rig_scene", nullptr, [&] {
        require_pointer(character_path, "character_path");
        require_pointer(scene_path, "scene_path");
        if (scene_path[0] == '\0') invalid("scene_path", "\"\"; expected the scene file to write (SCENE.json)");
        require_range(duration, 0.0, 3600.0, "duration", true);  // the scene format's (0, 3600] s
        if (chains != nullptr && chains_size == 0) invalid("chains_size", "0 with a chains buffer; expected its size in bytes");
        gltf::RigOptions options;
        options.clip = clip != nullptr ? clip : "";
        options.duration = duration;
        auto rig = gltf::make_rig_scene(character_path, scene_path, options);
        if (!rig.ok()) {
            // A file that cannot be read is the caller's argument, as one without chains.
            if (rig.error().kind == Error::Kind::Io) reject(KODAWARI_INVALID_ARGUMENT, rig.error().message);
            fail(rig.error());
        }
        const gltf::RigScene& r = rig.value();
        auto parsed = parse_scene(r.json, scene_path);
        if (!parsed.ok()) reject(KODAWARI_INTERNAL, "the scene written for " + std::string(character_path) +
                                                       " does not load: " + parsed.error().message);
        // Never over a file the scene reads (the character being rigged, its motions).
        // (The scene's own path is scene_path: only its inputs can clash.)
        for (const SceneInput& input : parsed.value().inputs) {
            if (!same_file(scene_path, input.path)) continue;
            invalid("scene_path", "\"" + std::string(scene_path) + "\" is " + input.what + ", which the scene reads; expected a .json path of its own");
        }
        auto out = AtomicFile::open(scene_path);
        if (!out.ok()) reject(KODAWARI_INVALID_ARGUMENT, out.error().message);
        out.value().write(r.json);
        auto done = out.value().commit();
        if (!done.ok()) reject(KODAWARI_INVALID_ARGUMENT, done.error().message);
        if (chains != nullptr) {
            std::string list;
            for (const gltf::RigChain& c : r.chains) {
                list += (list.empty() ? "" : "\n") + c.name + "\t" + c.root + "\t" + std::to_string(c.joints);
            }
            copy_text(list, chains, chains_size);
        }
    });
}

}  // extern "C"
