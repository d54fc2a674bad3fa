#pragma once
/// @file
/// Loading a user's rigged bird (`kodawari rig BIRD.glb --bird`, a flock's `"model"`;
/// docs/bird-models.md): its bones mapped onto the 7-part rig by name patterns or a
/// mapping file, its parts' axes and its wing measured, its flight derived.

#include <string>

#include "kodawari/core/api.hpp"
#include "kodawari/birds/bird_model.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::gltf {

/// Loads `path` (.gltf or .glb with a skin and a skinned mesh) as a bird. `map_path`
/// (may be empty) names a JSON object {"body": "bone", "head": ..., "left_upper_wing":
/// ...} whose parts take the named bones; the parts it leaves out are found by name
/// patterns. `mass` (kg, 0: estimated from the wing) goes to derive_flight().
/// Errors (InvalidInput unless the file cannot be read: Io) name the file and the glTF
/// or JSON path: no skin (`bird.glb: skins: ...`), a part no bone maps to, two parts on
/// one bone, a mapping file naming a bone the skin lacks (`map.json: $.head: ...`), no
/// mesh skinned to the bird's skin, wings that span 0 m.
[[nodiscard]] KODAWARI_API Result<birds::BirdModel> load_bird_model(const std::string& path, const std::string& map_path = {},
                                                                   float mass = 0.0f);

/// What `rig --bird` writes a scene of.
struct BirdSceneOptions {
    std::string name;        ///< the scene's and the flock's name
    std::string model_file;  ///< the flock's "model", relative to the scene's folder
    std::string map_file;    ///< its "map" (empty: none)
    /// The generated route's horizontal size (and the formation's and the camera's
    /// distance) as a multiple of the example's 90 m: `rig --bird` grows it until the bird
    /// can fly its turns at its cruise speed (kodawari/scene/route_check.hpp).
    float route_scale = 1.0f;
};

/// A scene (format version 1) with one flock of the model on a generated looping route,
/// as the scene format's example flock (docs/scene-format.md), as JSON text.
[[nodiscard]] KODAWARI_API std::string bird_scene_json(const BirdSceneOptions& options);

}  // namespace kodawari::gltf
