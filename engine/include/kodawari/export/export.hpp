#pragma once
/// @file
/// Outputs of a simulation: glTF 2.0 binary files with the animation baked, and JSON
/// Lines traces (docs/trace-format.md). Both are written atomically.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <kodawari/shared/birds.h>

#include "kodawari/core/api.hpp"
#include "kodawari/core/atomic_file.hpp"
#include "kodawari/core/communicator.hpp"
#include "kodawari/birds/world.hpp"
#include "kodawari/animation/character.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/rods/chain_snapshot.hpp"

namespace kodawari {

/// Compact animation keys (`kodawari run --compact`, docs/compact.md): per channel, the
/// keys that LINEAR interpolation between the kept ones reproduces within a bound are
/// dropped (first and last kept; glTF 2.0 Appendix C's lerp and slerp), and rotations are
/// written as normalized signed 16-bit integers, or 8-bit ones where the rotation bound
/// absorbs their rounding (up to 0.0158 rad) and that is smaller (§3.11 allows both for
/// rotation outputs; translations and scales stay floats, as the core spec requires). Each reduced channel
/// gets its own key times; channels keeping every frame, or only the first and the last,
/// share one accessor. Off by default: the file is then the uncompacted one, byte for
/// byte. The bounds, each >= 0 and finite: a point 1 m from a joint moves by at most
/// position_m + rotation_rad + scale_rel metres.
struct GlbCompaction {
    bool enabled = false;
    /// The distance between a dropped translation key and the interpolated one (metres).
    float position_m = 0.001f;
    /// The angle between a dropped rotation key and the interpolated one (radians),
    /// the rounding included (which alone is up to 6.1e-5 rad at 16 bits, 0.0158 rad at 8).
    float rotation_rad = 0.001f;
    /// A dropped scale key's difference from the interpolated one, per axis, relative to
    /// the key.
    float scale_rel = 0.001f;
    /// With `enabled` (`--compact --meshopt`): the keys also quantized per channel
    /// (rotations through meshopt's QUATERNION filter, translations and scales through its
    /// EXPONENTIAL one, the bits each channel's bound allows, the quantization counted in
    /// the bounds) and the key streams written with meshopt's attribute codec as
    /// EXT_meshopt_compression, a required extension: smaller, for the readers that decode
    /// it (three.js with its MeshoptDecoder, gltf-transform, Blender 5.2 and later).
    bool meshopt = false;
    /// The threads that reduce and encode the channels (0: one per core). The file's bytes
    /// are the same whatever the count.
    unsigned threads = 0;
};

/// What compaction did to one file: keys over all channels before and after, the
/// animation data's bytes (keys and key times) before and after, and the largest error
/// it introduced per kind (what re-importing and interpolating gives back, compared with
/// the uncompacted keys).
struct GlbCompactionStats {
    std::uint64_t keys = 0;
    std::uint64_t kept = 0;
    std::uint64_t bytes_before = 0;
    std::uint64_t bytes_after = 0;
    double position_m = 0.0;
    double rotation_rad = 0.0;
    double scale_rel = 0.0;
    /// Rotation channels, and those of them written as 8-bit integers.
    std::uint64_t rotations = 0;
    std::uint64_t byte_rotations = 0;
};

/// `path` without its `.glb` extension (any case), or `path` itself when it has none: what
/// a bake's other files are named after (`OUT-characters.glb`, `OUT-bird.glb`).
[[nodiscard]] KODAWARI_API std::string glb_stem(const std::string& path);

/// The glTF files a bake to `out` writes, as `kodawari run` and the C API's bake name
/// them: the birds at `out`; the characters at `out` too when there are no birds, else at
/// `glb_stem(out) + "-characters.glb"`.
[[nodiscard]] KODAWARI_API std::vector<std::string> glb_bake_paths(const std::string& out, bool has_birds, bool has_chains);

/// Why `out` cannot be a bake's output name, or "" when it can: a bake is binary glTF, so a
/// regular file (or a new one) is named `.glb` (any case; a `.gltf` is read as JSON glTF
/// by every importer); a device or a named pipe (/dev/null, a FIFO) has no name to go by.
[[nodiscard]] KODAWARI_API std::string glb_name_problem(const std::string& out);

/// InvalidInput naming `path` unless every bound of an enabled compaction is finite and
/// >= 0.
[[nodiscard]] KODAWARI_API Result<void> check_compaction(const std::string& path, const GlbCompaction& compaction);

/// Writes a `.glb`: per bird one armature (a root node named after the bird, the 7 parts
/// as joints), one skin and one mesh node; one skinned mesh per wing type (the parts'
/// meshes merged, each vertex on its part's joint) shared by every bird of the type; and
/// one animation sampled at every frame: the Body's translation, every part's rotation
/// and, when some bird spreads its tail, the Tail's scale (1 + s, 1, 1). Blender imports
/// one armature and one action per bird. `poses` holds `frames` x birds entries,
/// frame-major.
[[nodiscard]] KODAWARI_API Result<void> write_birds_glb(const std::string& path, const birds::BirdWorld& world,
                                                        std::span<const gpu::BirdPose> poses, std::uint32_t frames,
                                                        const GlbCompaction& compaction = {});

/// Streams write_birds_glb()'s file (the same bytes) frame by frame, so that memory does
/// not grow with frames x birds. Each frame's keys go to a temporary file beside `path`
/// (removed from the directory as soon as it is opened, so nothing is left behind);
/// finish() copies them into the `.glb`'s channels, channel after channel, through two
/// buffers of kTransposeBytes (more only when one bird's keys over all frames are more).
/// Besides that, it holds 272 bytes per bird (the first and the previous frame's keys)
/// and one frame's keys while adding; while finishing, the glTF model without the birds:
/// their nodes, accessors and animation channels are made one bird at a time while the
/// JSON is written to another temporary file beside `path`.
class KODAWARI_API BirdGlbWriter {
public:
    /// The size of each of the two buffers that reorder the keys from frame-major to
    /// channel-major.
    static constexpr std::size_t kTransposeBytes = std::size_t{32} << 20;

    /// Prepares `path` for `frames` frames of `world` (which must outlive the writer),
    /// its keys compacted as `compaction` says (default: not). Errors (naming `path`): no
    /// frames, fps not positive, more keys than a .glb can hold when not compacting (a
    /// compacted file's size is known only at finish(), which refuses one past 4 GiB
    /// before writing it), a bird of unknown wing type, bad compaction bounds
    /// (InvalidInput), the temporary file (Io).
    [[nodiscard]] static Result<BirdGlbWriter> create(const std::string& path, const birds::BirdWorld& world,
                                                      std::uint32_t frames, const GlbCompaction& compaction = {});

    BirdGlbWriter(BirdGlbWriter&& other) noexcept;
    BirdGlbWriter& operator=(BirdGlbWriter&& other) noexcept;
    BirdGlbWriter(const BirdGlbWriter&) = delete;
    BirdGlbWriter& operator=(const BirdGlbWriter&) = delete;
    ~BirdGlbWriter();

    /// Adds the next frames: `poses` holds whole frames of every bird, frame-major. A
    /// position that is not finite or a rotation that is not a quaternion is an
    /// Error::Kind::Internal naming the bird and frame; more frames than announced, or a
    /// partial frame, InvalidInput.
    [[nodiscard]] Result<void> add_frames(std::span<const gpu::BirdPose> poses);

    /// Writes the `.glb` atomically once every frame has been added. Call it once.
    [[nodiscard]] Result<void> finish();

    /// What compaction did, once finish() has written a compacted file (zeros else).
    [[nodiscard]] const GlbCompactionStats& compaction_stats() const;

    /// Distributed bakes (kodawari/simulation/distributed.hpp): whether the ranks can share this
    /// writer's work, each compacting its own birds' channels: compacted keys without
    /// meshopt (whose chunks span birds), every bird of a built-in wing type, and a file
    /// other processes can write into (not a device or a pipe).
    [[nodiscard]] bool can_share() const;
    /// Makes this the writer of one rank of a distributed bake, before the first frame:
    /// it keeps the keys of birds [begin, end) alone (this rank's shard, a contiguous
    /// range of the world's birds, as every rank's writer has been created on the whole
    /// world), and add_frames() takes whole frames of those birds. Errors: can_share()
    /// false, a range outside the world, frames added already (InvalidInput).
    [[nodiscard]] Result<void> share(std::size_t begin, std::size_t end);
    /// finish() of a shared writer, on every rank at once (collective): every rank
    /// compacts its birds' channels; rank 0 writes the header, the JSON and its own
    /// birds' keys, and each other rank writes its birds' keys into the file at the place
    /// agreed, before rank 0 renames it into place. The same bytes as one writer fed
    /// every bird. Every rank returns the same status.
    [[nodiscard]] Result<void> finish(Communicator& ranks);

private:
    struct Impl;
    explicit BirdGlbWriter(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

/// Writes a `.glb` of a rod scene: per character instance its skeleton as a node
/// hierarchy and, under each chain's attachment joint, the chain's joints as a
/// hierarchy (joint i the child of joint i-1) whose bones point at the next joint
/// (SPEC A.4's skinning output); one animation with translation and rotation channels
/// on every node, one key per frame. `positions` and `orientations` hold frames x
/// scene.world.joint_count world-space entries (ChainSnapshot's), frame-major.
[[nodiscard]] KODAWARI_API Result<void> write_chains_glb(const std::string& path, const RodScene& scene, std::uint32_t frames,
                                                         std::span<const glm::vec3> positions,
                                                         std::span<const glm::quat> orientations,
                                                         const GlbCompaction& compaction = {});

/// Points moving frame by frame as a `.glb`: a node named `name` holding one child node
/// per point (named `<name>.<i>`, a box `size` m wide), each with a LINEAR translation
/// animation over `frames` frames at `fps` (key k at k / fps s), the first frame its rest
/// translation. `positions`: frames x points, frame-major, finite. The output that fits
/// any domain whose instances are points (make_points_glb_sink() in kodawari/simulation/bake.hpp);
/// it holds every frame in memory. Written atomically.
[[nodiscard]] KODAWARI_API Result<void> write_points_glb(const std::string& path, const std::string& name, float fps,
                                                         std::uint32_t frames, std::span<const glm::vec3> positions,
                                                         float size = 0.05f);

/// Streams write_chains_glb()'s file (the same bytes) frame by frame, so that memory does
/// not grow with frames x joints: each frame's keys wait in a temporary file beside
/// `path` (SpillFile, unlinked at once, so nothing is left behind) and finish() copies
/// them into the `.glb`'s channels through two buffers of about kTransposeBytes (more
/// only when one node's keys over all frames are more). Besides that, it holds the glTF
/// model without its keys (nodes, meshes) and 84 bytes per animated node.
class KODAWARI_API ChainsGlbWriter {
public:
    /// The size of each of the two buffers that reorder the keys from frame-major to
    /// channel-major.
    static constexpr std::size_t kTransposeBytes = std::size_t{32} << 20;

    /// Prepares `path` for `frames` frames of `scene` (which must outlive the writer),
    /// its keys compacted as `compaction` says (default: not). Errors (naming `path`): no
    /// frames, more keys than a .glb can hold uncompacted (InvalidInput, with the size),
    /// bad compaction bounds (InvalidInput), the temporary file (Io).
    [[nodiscard]] static Result<ChainsGlbWriter> create(const std::string& path, const RodScene& scene, std::uint32_t frames,
                                                        const GlbCompaction& compaction = {});

    ChainsGlbWriter(ChainsGlbWriter&& other) noexcept;
    ChainsGlbWriter& operator=(ChainsGlbWriter&& other) noexcept;
    ChainsGlbWriter(const ChainsGlbWriter&) = delete;
    ChainsGlbWriter& operator=(const ChainsGlbWriter&) = delete;
    ~ChainsGlbWriter();

    /// Adds the next frame: scene.world.joint_count world-space positions and
    /// orientations (a ChainSnapshot's). Wrong sizes or more frames than announced:
    /// InvalidInput; a joint that comes out not finite: Internal, naming chain and frame.
    [[nodiscard]] Result<void> add_frame(std::span<const glm::vec3> positions, std::span<const glm::quat> orientations);

    /// Writes the `.glb` atomically once every frame has been added. Call it once.
    [[nodiscard]] Result<void> finish();

    /// What compaction did, once finish() has written a compacted file (zeros else).
    [[nodiscard]] const GlbCompactionStats& compaction_stats() const;

    /// Distributed bakes (kodawari/simulation/distributed.hpp), as BirdGlbWriter's: whether the
    /// ranks can share this writer's work (compacted keys without meshopt, an output that
    /// is not a device or a pipe).
    [[nodiscard]] bool can_share() const;
    /// Before the first frame: this rank keeps the keys of characters [begin, end) (scene
    /// instances) alone; add_frame() still takes the whole world's joints, of which only
    /// those characters' are read. Errors: can_share() false, a range outside the
    /// characters, frames added already (InvalidInput).
    [[nodiscard]] Result<void> share(std::size_t begin, std::size_t end);
    /// finish() of a shared writer, on every rank at once (collective): the same bytes as
    /// one writer fed every character. Every rank returns the same status.
    [[nodiscard]] Result<void> finish(Communicator& ranks);

private:
    struct Impl;
    explicit ChainsGlbWriter(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

/// One instance of a rigged character in a rigged export.
struct RiggedInstance {
    /// The name of the instance's root node and the prefix of its nodes' names. Distinct
    /// names let re-importers tell the instances apart; they are not checked.
    std::string name;
    /// Where the instance stands: the transform of its root node (world space).
    rods::Transform placement;
};

/// Writes a crowd of one rigged glTF character as a `.glb` with the simulated motion
/// baked into one animation, fed frame by frame. Between create() and finish() it holds
/// the source file's data (once, whatever the number of instances) and 17 bytes per
/// animated node and instance; the keys (40 bytes per animated node, instance and frame)
/// wait in a temporary file (SpillFile: beside the output when create() is told where,
/// unlinked at once, so nothing is left behind) and finish() copies them into the
/// `.glb` through two buffers of about kTransposeBytes (more only when one node's keys
/// over all frames are more).
///
/// What the file holds:
/// - The source's meshes, materials, textures, images, samplers, cameras, lights and
///   accessors, shared by all instances (not duplicated). All its buffers are merged into
///   the one GLB buffer; images given by URI (external files or data URIs) are moved into
///   buffer views, so the `.glb` is self-contained.
/// - Per instance, in instance order: a root node named after the instance carrying its
///   placement, then a copy of every node of the file in the file's order (file node n of
///   instance i is node output_node(i, n)), named "<instance>/<name>" ("<instance>/#<n>"
///   for a nameless node). The copies of the displayed scene's root nodes are the root
///   node's children; nodes outside the displayed scene are copied (skins may use them)
///   but, as in the source, not shown.
/// - Skinned mesh nodes at the scene root: skinning ignores a skinned mesh node's own
///   transform and its parents' (§3.7.3), and glTF-Validator warns about them elsewhere
///   (NODE_SKINNED_MESH_NON_ROOT). A childless, unanimated skinned mesh node that is not
///   a joint moves there and loses its transform; any other keeps its place in the
///   hierarchy without its mesh, which moves to an extra scene-root node
///   "<instance>/<name>/skinned mesh" (after the file's nodes, see output_node()).
///   Non-skinned mesh nodes stay in the hierarchy.
/// - Per instance a copy of every skin, named "<instance>/<name>" ("<instance>/skin"
///   for a nameless one), its joints and skeleton mapped to the instance's nodes; the
///   inverse bind matrices are shared.
/// - One scene (the source's displayed one): per instance its root node, then its
///   skinned mesh nodes.
/// - One animation named `animation_name` (none when no node is animated); the source's
///   animations are dropped. Every animated node of every instance gets a LINEAR
///   translation and rotation channel with a key per frame at time frame / fps, and a
///   scale channel unless every key equals the node's rest scale exactly (a scale that
///   never changes is left to the rest pose).
///   Rotations are normalized and kept in the hemisphere of the previous key, so that
///   players interpolate the short way. An animated node given by a matrix in the file is
///   written with the matrix decomposed into TRS (§3.5.3: animated nodes have no matrix;
///   exact for matrices without shear); other nodes keep their transform as written.
///   An animated node's rest transform stays the file's (the bind pose importers show).
/// - Extensions: VRM's (`VRM`, `VRMC_*`) refer to nodes of one character by index and
///   cannot follow the copies; they are removed from the root, nodes, materials, meshes,
///   primitives, textures, images and skins, and from extensionsUsed/extensionsRequired
///   (MToon materials fall back to their glTF PBR values). The VRM `meta` object (author,
///   license) is kept as `asset.extras.vrmMeta`. Every other extension and every `extras`
///   is copied as it is (KHR_materials_*, KHR_texture_transform, ...).
/// - The source's other scenes are dropped. The keys of its animations stay in the
///   buffer, unreferenced (accessors are kept as they are, since extensions may name
///   them by index; glTF-Validator reports them as UNUSED_OBJECT infos).
class KODAWARI_API RiggedGlbWriter {
public:
    /// Loads the character file (.gltf with external or data-URI buffers and images, .glb
    /// or .vrm) whose data are copied. `character` is the same file loaded by
    /// gltf::load_character (its node indices are the file's); `animated` has one entry
    /// per node: true gives the node channels. `fps` > 0 spaces the keys.
    /// Errors: the file does not load, or does not match `character`; an image it
    /// references cannot be read (Error::Kind::InvalidInput or Io, naming the file); it
    /// uses EXT_meshopt_compression (Unsupported: its buffer indices cannot survive the
    /// merge into one buffer); a placement is not finite (InvalidInput).
    /// `spill_beside`: the output's path, beside which the keys wait (empty: the
    /// system's temporary directory); a failure to create that file is an Io error of
    /// the first add_frame(). `compaction`: the keys compacted (default: not; bad
    /// bounds are InvalidInput).
    [[nodiscard]] static Result<RiggedGlbWriter> create(const std::string& source_path, const animation::Character& character,
                                                        std::span<const RiggedInstance> instances,
                                                        std::vector<bool> animated, float fps,
                                                        std::string animation_name, std::string spill_beside = {},
                                                        const GlbCompaction& compaction = {});

    /// The size of the buffer that reorders the keys from frame-major to per node.
    static constexpr std::size_t kTransposeBytes = std::size_t{32} << 20;

    RiggedGlbWriter(RiggedGlbWriter&& other) noexcept;
    RiggedGlbWriter& operator=(RiggedGlbWriter&& other) noexcept;
    RiggedGlbWriter(const RiggedGlbWriter&) = delete;
    RiggedGlbWriter& operator=(const RiggedGlbWriter&) = delete;
    ~RiggedGlbWriter();

    /// Adds one frame: the local TRS of every node of every instance (instances x nodes,
    /// instance-major), relative to the node's parent in the file's hierarchy (a root of
    /// the file: relative to the instance's placement). Only the animated nodes' values
    /// are used; the spans must hold instances x nodes entries each (asserted). An
    /// animated node's value that is not finite, or a zero rotation, is an
    /// Error::Kind::InvalidInput naming the frame, instance and node (the frame is not
    /// added).
    [[nodiscard]] Result<void> add_frame(std::span<const glm::vec3> translation, std::span<const glm::quat> rotation,
                                         std::span<const glm::vec3> scale);

    /// Writes the `.glb` atomically (a temporary file renamed into place; nothing is left
    /// behind on failure). Needs at least one frame. Call it once: it moves the source's
    /// data into the file; only a failure to open `path` leaves the writer usable for
    /// another try. Errors name `path`.
    [[nodiscard]] Result<void> finish(const std::string& path);

    /// The frames added so far.
    [[nodiscard]] std::uint32_t frames() const;
    /// What compaction did, once finish() has written a compacted file (zeros else).
    [[nodiscard]] const GlbCompactionStats& compaction_stats() const;
    /// The index in the written file of node `node` of the file for instance `instance`;
    /// -1 as `node` gives the instance's root node. For a skinned mesh whose node stayed
    /// in the hierarchy, skinned_mesh_node() gives the node holding the mesh.
    [[nodiscard]] int output_node(std::size_t instance, int node) const;
    /// The index in the written file of the node holding file node `node`'s skinned mesh
    /// for `instance` (the node itself when it moved to the scene root, else its extra
    /// node); -1 when `node` has no skinned mesh.
    [[nodiscard]] int skinned_mesh_node(std::size_t instance, int node) const;

    /// Distributed bakes (kodawari/simulation/distributed.hpp), as BirdGlbWriter's: whether the
    /// ranks can share this writer's work, each compacting its own instances' channels
    /// (compacted keys without meshopt, animated nodes, and an output that is not a device
    /// or a pipe).
    [[nodiscard]] bool can_share() const;
    /// Before the first frame: this rank keeps the keys of instances [begin, end) alone,
    /// and add_frame() takes the values of those instances only. Errors: can_share()
    /// false, a range outside the instances, frames added already (InvalidInput).
    [[nodiscard]] Result<void> share(std::size_t begin, std::size_t end);
    /// finish(path) of a shared writer, on every rank at once (collective; shared_glb):
    /// the same bytes as one writer fed every instance. Every rank returns the same status.
    [[nodiscard]] Result<void> finish(Communicator& ranks, const std::string& path);

private:
    struct Impl;
    explicit RiggedGlbWriter(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

/// The birds of one user's model (BirdWorld::models[model], docs/bird-models.md) baked
/// into a RiggedGlbWriter: the model's own meshes, materials, textures and skins written
/// once and shared, per bird a copy of its node hierarchy (one armature per bird, named
/// "<model>_<bird index>"), and one animation "flight" keying the 7 mapped bones: the
/// Body's bone placed in the world by the bird's Body pose, every other mapped bone
/// turned by its part's rotation carried into the bone's frame (model_bone_rotation),
/// the tail bone scaled by the spread (1 + s along its axis nearest the rig's width);
/// the other bones stay at rest.
class KODAWARI_API BirdModelExport {
public:
    /// Errors: no bird of the model, the model's file (RiggedGlbWriter::create's).
    [[nodiscard]] static Result<BirdModelExport> create(const birds::BirdWorld& world, std::size_t model,
                                                        const std::string& path, const GlbCompaction& compaction = {});
    /// Whole frames of every bird of the world, frame-major (as BirdGlbWriter takes them).
    [[nodiscard]] Result<void> add_frames(std::span<const gpu::BirdPose> poses);
    [[nodiscard]] Result<void> finish();
    [[nodiscard]] const std::string& path() const { return path_; }
    [[nodiscard]] const GlbCompactionStats& compaction_stats() const { return writer_.compaction_stats(); }

private:
    BirdModelExport(const birds::BirdWorld& world, std::size_t model, std::string path, std::vector<std::uint32_t> birds,
                    RiggedGlbWriter writer);
    const birds::BirdWorld* world_;
    std::size_t model_;
    std::string path_;
    std::vector<std::uint32_t> birds_;  // the model's birds, world indices
    RiggedGlbWriter writer_;
    glm::mat4 body_parent_inverse_{1.0f};  // inverse rest world matrix of the Body bone's parent
    std::vector<glm::vec3> translation_, scale_;
    std::vector<glm::quat> rotation_;
};

/// The simulated crowd of one rigged character template of a RodScene, baked into a
/// RiggedGlbWriter (issue 4): every instance of the template with the file's own
/// skeleton, skins and meshes; the nodes its clips animate keyed from the clip, and the
/// simulated chain joints keyed from the simulation, so that the character's own skinned
/// mesh follows the strands.
///
/// A simulated joint i >= 1 of a chain gets the world position the solver computed and
/// the particle's orientation turned by the shortest arc that points its bone (the rest
/// direction to joint i + 1, Chain::bone_axis) at the next joint, as write_chains_glb()
/// does (SPEC A.4's skinning output); the last joint keeps the particle's orientation.
/// Its local transform is then taken relative to its parent's world matrix (simulated
/// or animated), with the node's animated local scale kept. Joint 0 follows its clip.
/// Re-importing the file and evaluating its animation gives these world transforms back
/// (tests: within 1e-5 of the character's size).
class KODAWARI_API RiggedCrowdExport {
public:
    /// Prepares the export of RodScene::characters[character] (which must be rigged).
    /// `scene` must outlive the export. `output`: the path finish() will be given, beside
    /// which the keys wait (RiggedGlbWriter::create's `spill_beside`). `compaction`: the
    /// keys compacted (default: not). Errors: those of RiggedGlbWriter::create.
    [[nodiscard]] static Result<RiggedCrowdExport> create(const RodScene& scene, std::uint32_t character,
                                                          const std::string& output = {},
                                                          const GlbCompaction& compaction = {});

    /// Adds frame `frame` of the scene: the clip poses at that frame and the chains of
    /// `snapshot` (the rod backend's state after that frame, for the whole world).
    [[nodiscard]] Result<void> add_frame(std::uint32_t frame, const ChainSnapshot& snapshot);

    /// Writes the `.glb` atomically (RiggedGlbWriter::finish).
    [[nodiscard]] Result<void> finish(const std::string& path);

    /// Distributed bakes: RiggedGlbWriter::can_share().
    [[nodiscard]] bool can_share() const { return writer_.can_share(); }
    /// Distributed bakes, before the first frame: this rank poses and keeps instances
    /// [begin, end) of instances() alone; add_frame()'s snapshot must still be indexed as
    /// the whole world's (only those instances' joints are read). Errors:
    /// RiggedGlbWriter::share's.
    [[nodiscard]] Result<void> share(std::size_t begin, std::size_t end);
    /// finish(path) on every rank at once (RiggedGlbWriter::finish(ranks, path)).
    [[nodiscard]] Result<void> finish(Communicator& ranks, const std::string& path) { return writer_.finish(ranks, path); }

    /// The instances written, in order: indices into RodScene::instances.
    [[nodiscard]] const std::vector<std::uint32_t>& instances() const { return instances_; }
    /// The writer (for its node mapping).
    [[nodiscard]] const RiggedGlbWriter& writer() const { return writer_; }

private:
    RiggedCrowdExport(const RodScene& scene, std::uint32_t character, std::vector<std::uint32_t> instances,
                      RiggedGlbWriter writer);

    const RodScene* scene_;
    std::uint32_t character_;
    std::vector<std::uint32_t> instances_;
    std::size_t own_begin_ = 0;  // the instances this rank poses (share())
    std::size_t own_end_ = 0;
    RiggedGlbWriter writer_;
    // Per-frame scratch, instances x nodes.
    std::vector<glm::vec3> translation_, scale_;
    std::vector<glm::quat> rotation_;
};

/// What the first line of a trace says.
struct TraceHeader {
    std::string scene;
    float fps = 60.0f;
    std::uint32_t frames = 0;
    std::string backend;
};

/// Streams a JSON Lines trace: a header line, then one line per bird and frame.
class KODAWARI_API TraceWriter {
public:
    /// Opens the (temporary) file and writes the header line.
    [[nodiscard]] static Result<TraceWriter> open(const std::string& path, const TraceHeader& header);

    /// Appends the records of one frame; `poses` and `diag` hold one entry per bird.
    void write_frame(std::uint32_t frame, const birds::BirdWorld& world, std::span<const gpu::BirdPose> poses,
                     std::span<const gpu::BirdDiag> diag);

    /// Appends one chain record per chain of one frame (docs/trace-format.md): for chain
    /// c its character instance characters[c], its index chains_in_character[c] within
    /// that character, its name (names may be empty), and the snapshot's view direction,
    /// weights, rest shape, joints and orientations (world space).
    void write_chains(std::uint32_t frame, float time, const rods::RodWorld& world, std::span<const std::uint32_t> characters,
                      std::span<const std::uint32_t> chains_in_character, std::span<const std::string> names,
                      const ChainSnapshot& snapshot);

    /// Completes the file (renames it into place).
    [[nodiscard]] Result<void> finish();

private:
    explicit TraceWriter(AtomicFile file) : file_(std::move(file)) {}
    AtomicFile file_;
    std::string buffer_;
};

}  // namespace kodawari
