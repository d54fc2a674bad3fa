// Pieces shared by the glTF writers.
#include "export/gltf_common.hpp"
#include "export/gltf_json_stream.hpp"

#include <algorithm>
#include <cassert>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

namespace kodawari::gltf {
namespace {

/// An ostream that appends to an AtomicFile, so the GLB goes to disk without a second
/// in-memory copy of a buffer that can reach a gigabyte.
class AtomicFileBuf : public std::streambuf {
public:
    explicit AtomicFileBuf(AtomicFile& file) : file_(file) {}

protected:
    std::streamsize xsputn(const char* data, std::streamsize count) override {
        file_.write(data, static_cast<std::size_t>(count));
        return count;
    }
    int_type overflow(int_type ch) override {
        if (traits_type::eq_int_type(ch, traits_type::eof())) return traits_type::not_eof(ch);
        const char c = traits_type::to_char_type(ch);
        file_.write(&c, 1);
        return ch;
    }

private:
    AtomicFile& file_;
};
}  // namespace

std::size_t BufferWriter::allocate(std::size_t size) {
    const std::size_t offset = bytes_.size();
    bytes_.resize(offset + ((size + 3) & ~std::size_t{3}));
    return offset;
}

std::size_t BufferWriter::append(const void* data, std::size_t size) {
    const std::size_t offset = allocate(size);
    std::memcpy(bytes_.data() + offset, data, size);
    return offset;
}

int add_buffer_view(tinygltf::Model& model, std::size_t offset, std::size_t length, int target) {
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = offset;
    view.byteLength = length;
    view.target = target;
    model.bufferViews.push_back(std::move(view));
    return static_cast<int>(model.bufferViews.size() - 1);
}

int add_accessor(tinygltf::Model& model, int view, std::size_t offset, int component, std::size_t count,
                 int type) {
    tinygltf::Accessor accessor;
    accessor.bufferView = view;
    accessor.byteOffset = offset;
    accessor.componentType = component;
    accessor.count = count;
    accessor.type = type;
    model.accessors.push_back(std::move(accessor));
    return static_cast<int>(model.accessors.size() - 1);
}

/// Float VEC3 accessor with its own ARRAY_BUFFER view, min/max filled in.
int add_vec3_attribute(tinygltf::Model& model, BufferWriter& writer, const std::vector<Vec3>& values) {
    const std::size_t bytes = values.size() * sizeof(Vec3);
    const std::size_t offset = writer.append(values.data(), bytes);
    const int view = add_buffer_view(model, offset, bytes, kArrayBuffer);
    const int accessor =
        add_accessor(model, view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, values.size(), TINYGLTF_TYPE_VEC3);
    std::vector<double> lo(3, std::numeric_limits<double>::max());
    std::vector<double> hi(3, std::numeric_limits<double>::lowest());
    for (const Vec3& v : values) {
        for (int i = 0; i < 3; ++i) {
            lo[i] = std::min(lo[i], static_cast<double>(v[i]));
            hi[i] = std::max(hi[i], static_cast<double>(v[i]));
        }
    }
    model.accessors[accessor].minValues = std::move(lo);
    model.accessors[accessor].maxValues = std::move(hi);
    return accessor;
}


int add_mesh(tinygltf::Model& model, BufferWriter& writer, const MeshData& data, int material, const std::string& name) {
    assert(data.positions.size() <= std::numeric_limits<std::uint16_t>::max());
    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    primitive.material = material;
    primitive.attributes["POSITION"] = add_vec3_attribute(model, writer, data.positions);
    primitive.attributes["NORMAL"] = add_vec3_attribute(model, writer, data.normals);
    const std::size_t index_bytes = data.indices.size() * sizeof(std::uint16_t);
    const std::size_t offset = writer.append(data.indices.data(), index_bytes);
    const int view = add_buffer_view(model, offset, index_bytes, kElementArrayBuffer);
    primitive.indices = add_accessor(model, view, 0, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, data.indices.size(),
                                     TINYGLTF_TYPE_SCALAR);
    tinygltf::Mesh mesh;
    mesh.name = name;
    mesh.primitives.push_back(std::move(primitive));
    model.meshes.push_back(std::move(mesh));
    return static_cast<int>(model.meshes.size() - 1);
}

Result<void> write_glb(AtomicFile& file, tinygltf::Model& model) {
    AtomicFileBuf buffer(file);
    std::ostream stream(&buffer);
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&model, stream, false, true) || !stream) {
        return make_error(Error::Kind::Io, file.path() + ": glTF serialization failed");
    }
    return {};
}

Result<void> write_glb_with_tail(AtomicFile& file, tinygltf::Model& model, std::uint64_t tail_bytes,
                                 const std::function<Result<void>()>& write_tail, const MeshoptJson* meshopt) {
    // The streamed writer with nothing streamed: one framing of the container, and the
    // JSON never held twice (tinygltf's DOM and string of a large model).
    StreamedElements streamed;
    if (meshopt != nullptr) streamed.meshopt = *meshopt;
    return write_streamed_glb(file, model, streamed, tail_bytes, write_tail);
}

Result<SpillFile> SpillFile::open(const std::string& beside) {
    SpillFile spill;
    // Beside the output, on the disk meant to hold it; in the temporary directory when
    // there is no output path or the output is a device or a pipe (no files in /dev).
    struct stat existing {};
    const bool regular = beside.empty() || ::stat(beside.c_str(), &existing) != 0 || S_ISREG(existing.st_mode);
    const std::string base =
        beside.empty() || !regular ? (std::filesystem::temp_directory_path() / "kodawari").string() : beside;
    // A name of its own (mkstemp: O_EXCL), so that writers beside one output in one
    // process (the ranks of a distributed bake run as threads) never share a file.
    std::string name = base + ".keys-" + std::to_string(static_cast<long>(::getpid())) + "-XXXXXX";
    // Errors name the output the file serves (the file itself never has a name for long).
    spill.serves_ = beside;
    const int fd = ::mkstemp(name.data());
    spill.path_ = name;
    if (fd < 0) {
        // The output's folder is what the reader can act on; the temporary file's random
        // name is not (and was never made).
        const std::string folder = std::filesystem::path(name).parent_path().string();
        return make_error(Error::Kind::Io, (beside.empty() ? std::string("the keys") : beside) + ": cannot create a file in " +
                                               (folder.empty() ? std::string("the working folder") : folder) + " (" +
                                               std::strerror(errno) + ")");
    }
    spill.file_ = ::fdopen(fd, "w+b");
    if (spill.file_ == nullptr) {
        const int saved = errno;
        ::close(fd);
        std::remove(name.c_str());
        return make_error(Error::Kind::Io, spill.spill_error("cannot create", std::strerror(saved)));
    }
    std::remove(spill.path_.c_str());
    return spill;
}

SpillFile::SpillFile(SpillFile&& other) noexcept
    : file_(std::exchange(other.file_, nullptr)), path_(std::move(other.path_)), serves_(std::move(other.serves_)),
      reading_(other.reading_) {}

SpillFile& SpillFile::operator=(SpillFile&& other) noexcept {
    std::swap(file_, other.file_);
    std::swap(path_, other.path_);
    std::swap(serves_, other.serves_);
    std::swap(reading_, other.reading_);
    return *this;
}

SpillFile::~SpillFile() {
    if (file_ != nullptr) std::fclose(file_);
}

Result<void> SpillFile::append(const void* data, std::size_t size) {
    if (reading_) return make_error(Error::Kind::Internal, spill_error("cannot write", "appended to after reading"));
    if (std::fwrite(data, 1, size, file_) != size) return make_error(Error::Kind::Io, spill_error("cannot write", std::strerror(errno)));
    return {};
}

Result<void> SpillFile::read(std::uint64_t offset, void* data, std::size_t size) {
    if (!reading_ && std::fflush(file_) != 0) return make_error(Error::Kind::Io, spill_error("cannot write", std::strerror(errno)));
    reading_ = true;
    if (::fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0) {
        return make_error(Error::Kind::Io, spill_error("cannot read back", std::strerror(errno)));
    }
    if (std::fread(data, 1, size, file_) != size) {
        return make_error(Error::Kind::Io, spill_error("cannot read back", std::ferror(file_) ? std::strerror(errno) : "it is shorter than written"));
    }
    return {};
}

std::string SpillFile::spill_error(const std::string& what, const std::string& why) const {
    return (serves_.empty() ? what + " the" : serves_ + ": " + what + " its") + " temporary file " + path_ + " (" + why + ")";
}

void add_linear_channel(tinygltf::Animation& animation, int input, int output, int node, const char* path) {
    tinygltf::AnimationSampler sampler;
    sampler.input = input;
    sampler.output = output;
    sampler.interpolation = "LINEAR";
    animation.samplers.push_back(std::move(sampler));
    tinygltf::AnimationChannel channel;
    channel.sampler = static_cast<int>(animation.samplers.size() - 1);
    channel.target_node = node;
    channel.target_path = path;
    animation.channels.push_back(std::move(channel));
}

Result<void> write_file_atomically(const std::string& path, const std::function<Result<void>(AtomicFile&)>& build) {
    auto file = AtomicFile::open(path);
    if (!file) return file.error();
    try {
        KW_TRY(build(file.value()));
    } catch (const std::bad_alloc&) {
        return make_error(Error::Kind::Io, path + ": out of memory while building the glTF file");
    } catch (const std::exception& e) {
        return make_error(Error::Kind::Io, path + ": glTF serialization failed (" + e.what() + ")");
    }
    return file.value().commit();
}

Result<void> read_item_group(SpillFile& keys, std::size_t count, std::uint32_t frames, std::size_t record_floats,
                             std::size_t begin, std::size_t n, float* in) {
    const std::size_t record_bytes = record_floats * sizeof(float);
    // One contiguous run per frame: the group's records of that frame.
    for (std::uint32_t f = 0; f < frames; ++f) {
        KW_TRY(keys.read((std::uint64_t{f} * count + begin) * record_bytes, in + std::size_t{f} * n * record_floats,
                         n * record_bytes));
    }
    return {};
}

Result<void> copy_item_major(SpillFile& keys, AtomicFile& file, std::size_t count, std::uint32_t frames,
                             std::span<const std::size_t> fields, std::size_t group_bytes,
                             const std::function<bool(std::size_t item, std::size_t field)>& keep) {
    std::size_t record_floats = 0;
    for (const std::size_t n : fields) record_floats += n;
    const std::size_t record_bytes = record_floats * sizeof(float);
    const std::size_t group = std::max<std::size_t>(1, group_bytes / (std::size_t{frames} * record_bytes));
    std::vector<float> in(std::min(group, count) * std::size_t{frames} * record_floats);
    std::vector<float> out(in.size());
    for (std::size_t begin = 0; begin < count; begin += group) {
        const std::size_t n = std::min(group, count - begin);
        KW_TRY(read_item_group(keys, count, frames, record_floats, begin, n, in.data()));
        float* o = out.data();
        for (std::size_t item = 0; item < n; ++item) {
            std::size_t offset = 0;
            for (std::size_t field = 0; field < fields.size(); ++field) {
                const std::size_t width = fields[field];
                if (!keep || keep(begin + item, field)) {
                    for (std::uint32_t f = 0; f < frames; ++f, o += width) {
                        std::memcpy(o, in.data() + (std::size_t{f} * n + item) * record_floats + offset, width * sizeof(float));
                    }
                }
                offset += width;
            }
        }
        file.write(out.data(), static_cast<std::size_t>(o - out.data()) * sizeof(float));
    }
    return {};
}

}  // namespace kodawari::gltf
