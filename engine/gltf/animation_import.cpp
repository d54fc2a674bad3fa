// The animations of a glTF model: channels on node TRS and their samplers' keys.

#include <algorithm>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "gltf/import_detail.hpp"

namespace kodawari::gltf::detail {
namespace {

Result<animation::Sampler> load_sampler(const Context& ctx, const tinygltf::Model& model, const tinygltf::AnimationSampler& src,
                             const std::string& path, animation::Path target) {
    animation::Sampler sampler;
    if (src.interpolation == "LINEAR") {
        sampler.interpolation = animation::Interpolation::Linear;
    } else if (src.interpolation == "STEP") {
        sampler.interpolation = animation::Interpolation::Step;
    } else if (src.interpolation == "CUBICSPLINE") {
        sampler.interpolation = animation::Interpolation::CubicSpline;
    } else {
        return ctx.invalid(path + ".interpolation", "expected LINEAR, STEP or CUBICSPLINE, got \"" + src.interpolation + "\"");
    }
    auto times = read_floats(ctx, model, src.input, path + ".input", false);
    if (!times) return times.error();
    if (accessor_of(model, src.input).type != TINYGLTF_TYPE_SCALAR) {
        return ctx.invalid(path + ".input", "accessor " + std::to_string(src.input) + " is " +
                                                type_name(accessor_of(model, src.input).type) + ", expected SCALAR");
    }
    sampler.times = std::move(times).value();
    const bool cubic = sampler.interpolation == animation::Interpolation::CubicSpline;
    if (sampler.times.empty() || (cubic && sampler.times.size() < 2)) {
        return ctx.invalid(path + ".input", cubic ? "CUBICSPLINE needs at least two keys" : "no keys");
    }
    // §3.11: input times are strictly increasing.
    for (std::size_t k = 1; k < sampler.times.size(); ++k) {
        if (!(sampler.times[k] > sampler.times[k - 1])) {
            return ctx.invalid(path + ".input", "key times must increase: time " + std::to_string(k) + " is " +
                                                    std::to_string(sampler.times[k]) + " after " +
                                                    std::to_string(sampler.times[k - 1]));
        }
    }
    const std::size_t comps = target == animation::Path::Rotation ? 4 : 3;
    auto values = read_floats(ctx, model, src.output, path + ".output", target == animation::Path::Rotation);
    if (!values) return values.error();
    const tinygltf::Accessor& output = accessor_of(model, src.output);
    if (component_count(output.type) != comps || output.type == TINYGLTF_TYPE_MAT2) {
        return ctx.invalid(path + ".output", "accessor " + std::to_string(src.output) + " is " + type_name(output.type) +
                                                 ", a " + (target == animation::Path::Rotation ? "rotation needs VEC4" : "translation or scale needs VEC3"));
    }
    const std::size_t expected = sampler.times.size() * (cubic ? 3 : 1);
    if (output.count != expected) {
        return ctx.invalid(path + ".output", "accessor " + std::to_string(src.output) + " has " + std::to_string(output.count) +
                                                 " values, " + std::to_string(sampler.times.size()) + " keys" +
                                                 (cubic ? " of CUBICSPLINE" : "") + " need " + std::to_string(expected));
    }
    const std::vector<float>& f = values.value();
    sampler.values.resize(expected, glm::vec4(0.0f));
    for (std::size_t i = 0; i < expected; ++i) {
        for (std::size_t c = 0; c < comps; ++c) sampler.values[i][static_cast<int>(c)] = f[i * comps + c];
    }
    return sampler;
}

}  // namespace

Result<void> load_animations(const Context& ctx, const tinygltf::Model& model, animation::Character& out) {
    for (std::size_t a = 0; a < model.animations.size(); ++a) {
        const tinygltf::Animation& src = model.animations[a];
        const std::string path = at("$.animations", a);
        animation::Animation animation;
        // Scenes pick clips by name, so an unnamed clip gets one (see Animation::name).
        animation.name = src.name.empty() ? "animation" + std::to_string(a) : src.name;
        animation.samplers.resize(src.samplers.size());
        std::vector<int> sampler_path(src.samplers.size(), -1);  // the Path a sampler was loaded for
        bool any = false;
        for (std::size_t c = 0; c < src.channels.size(); ++c) {
            const tinygltf::AnimationChannel& channel = src.channels[c];
            const std::string cpath = at(path + ".channels", c);
            if (channel.sampler < 0 || static_cast<std::size_t>(channel.sampler) >= src.samplers.size()) {
                return ctx.invalid(cpath + ".sampler", "sampler " + std::to_string(channel.sampler) + " does not exist");
            }
            if (channel.target_node < 0) continue;  // §3.11: no node = targeted by an extension
            if (static_cast<std::size_t>(channel.target_node) >= out.nodes.size()) {
                return ctx.invalid(cpath + ".target.node", "node " + std::to_string(channel.target_node) + " does not exist");
            }
            animation::Path target = animation::Path::Translation;
            if (channel.target_path == "translation") {
                target = animation::Path::Translation;
            } else if (channel.target_path == "rotation") {
                target = animation::Path::Rotation;
            } else if (channel.target_path == "scale") {
                target = animation::Path::Scale;
            } else if (channel.target_path == "weights") {
                continue;  // morph targets do not move joints
            } else {
                return ctx.invalid(cpath + ".target.path", "expected translation, rotation, scale or weights, got \"" +
                                                               channel.target_path + "\"");
            }
            if (out.nodes[static_cast<std::size_t>(channel.target_node)].matrix) {
                return ctx.invalid(cpath + ".target.node", "node " + std::to_string(channel.target_node) +
                                                               " has a matrix; an animated node must use TRS (§3.5.3)");
            }
            for (const animation::Channel& other : animation.channels) {
                if (other.node == channel.target_node && other.path == target) {
                    return ctx.invalid(cpath + ".target", "node " + std::to_string(channel.target_node) + "'s " +
                                                              channel.target_path + " is animated twice in this animation");
                }
            }
            const auto s = static_cast<std::size_t>(channel.sampler);
            const int wanted = target == animation::Path::Rotation ? 4 : 3;
            if (sampler_path[s] < 0) {
                auto sampler = load_sampler(ctx, model, src.samplers[s], at(path + ".samplers", s), target);
                if (!sampler) return sampler.error();
                animation.samplers[s] = std::move(sampler).value();
                sampler_path[s] = wanted;
            } else if (sampler_path[s] != wanted) {
                return ctx.invalid(cpath + ".sampler", "sampler " + std::to_string(s) +
                                                           " also drives a property of another size");
            }
            animation.channels.push_back({channel.target_node, target, s});
            const animation::Sampler& used = animation.samplers[s];
            animation.start = any ? std::min(animation.start, used.times.front()) : used.times.front();
            animation.end = any ? std::max(animation.end, used.times.back()) : used.times.back();
            any = true;
        }
        out.animations.push_back(std::move(animation));
    }
    return {};
}

}  // namespace kodawari::gltf::detail
