// The cpu rod backend: engine/simd/rods_simd.cpp's kernel on every core. It keeps the
// chains in its own structure-of-arrays layout (simd/rods_simd.hpp: batches of 16 chains
// of one template), gathers each frame's input into it, and converts back only when the
// state is read. Threads take contiguous ranges of whole batches, balanced by their cost,
// so no two threads write the same cache line and the result never depends on the split.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include <hwy/aligned_allocator.h>

#include "backends/backends.hpp"
#include "core/parallel.hpp"
#include "simd/rods_simd.hpp"

namespace kodawari {
namespace {

using simd::kBatchLanes;

constexpr std::size_t kWeightCount = rods::kMaxViewExamples + 1;
constexpr float kRootShapeWeight = 10.0f;  // solver.cpp's

std::array<float, 4> xyzw(glm::quat q) { return {q.x, q.y, q.z, q.w}; }

// A template's constants, with engine/rods' own expressions (solver.cpp step, shape.cpp).
simd::RodTemplateConsts template_consts(const rods::ChainTemplate& t) {
    simd::RodTemplateConsts k;
    const rods::Chain& chain = t.chain;
    const std::uint32_t n = chain.joint_count;
    k.joints = n;
    k.views = static_cast<std::uint32_t>(t.views.size());
    k.keyed = static_cast<std::uint32_t>(t.keyed.size());
    k.thickness = chain.thickness;
    k.b2 = chain.thickness * chain.thickness;
    k.suppression = t.params.momentum_suppression;
    k.first_direction = {t.basis.first_direction.x, t.basis.first_direction.y, t.basis.first_direction.z};
    for (std::uint32_t j = 0; j < n; ++j) {
        k.weight[j] = j == 0 ? kRootShapeWeight * chain.mass[0] : chain.mass[j];
        k.weight5[j] = k.weight[j] / 5.0f;
        const float a2 = chain.half_length[j] * chain.half_length[j];
        k.ab[j] = a2 - k.b2;
        k.segment[j] = chain.segment_length[j];
        k.bone_axis[j] = {chain.bone_axis[j].x, chain.bone_axis[j].y, chain.bone_axis[j].z};
        if (j + 1 < n) k.lengths[j] = t.basis.lengths[j];
        k.limit_kind[j] = static_cast<std::uint32_t>(chain.limit[j].kind);
        k.limit_trig[j] = {chain.limit_trig[j].x, chain.limit_trig[j].y, chain.limit_trig[j].z, chain.limit_trig[j].w};
        k.limit_frame[j] = xyzw(chain.limit_frame[j]);
    }
    k.limited = chain.limited;
    k.drag = t.params.normal_drag > 0.0f || t.params.tangent_drag > 0.0f;
    // What split_threads() weighs before the first step's set_step().
    k.step.iterations = t.params.iterations;
    k.reduced.iterations = rods::reduced_params(t.params).iterations;
    for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint32_t lo = i == 0 ? 0 : i - 1;
        const std::uint32_t hi = std::min(i + 1, n - 1);
        float mass = 0.0f;
        for (std::uint32_t j = lo; j <= hi; ++j) mass += k.weight[j];
        k.group_mass[i] = mass;
    }
    for (std::size_t v = 0; v < t.views.size(); ++v) {
        k.view_direction[v] = {t.views[v].direction.x, t.views[v].direction.y, t.views[v].direction.z};
        k.influence[v] = t.views[v].influence;
    }
    const rods::RotationShape& base = t.shapes[0];
    for (const rods::RotationShape& s : t.shapes) {
        for (std::uint32_t i = 0; i < n; ++i) {
            const glm::quat r = i + 1 < n ? s.rotations[i] : glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
            const glm::quat r0 = i + 1 < n ? base.rotations[i] : glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
            k.rotation.push_back(xyzw(r));
            k.orientation.push_back(xyzw(s.orientations[i]));
            // shape.cpp blend_one's hemisphere test.
            k.rotation_sign.push_back(glm::dot(r, r0) < 0.0f ? -1.0f : 1.0f);
            k.orientation_sign.push_back(glm::dot(s.orientations[i], base.orientations[i]) < 0.0f ? -1.0f : 1.0f);
        }
    }
    if (t.views.empty() && t.keyed.empty()) {
        const rods::ChainShape rest = rods::to_positions(t.basis, rods::blend(t.shapes, rods::view_weights({}, {})));
        for (std::uint32_t i = 0; i < n; ++i) {
            k.fixed_rest_position.push_back({rest.positions[i].x, rest.positions[i].y, rest.positions[i].z});
            k.fixed_rest_orientation.push_back(xyzw(rest.orientations[i]));
        }
    }
    return k;
}

// The step sizes of a frame of `dt`, as rods::step computes them.
void set_step(simd::RodStepConsts& k, const rods::SolverParams& p, float dt) {
    k.iterations = p.iterations;
    k.substeps = std::max(1u, static_cast<std::uint32_t>(std::ceil(dt / p.max_substep)));
    k.h = dt / static_cast<float>(k.substeps);
    k.k_iter = rods::iteration_stiffness(rods::substep_stiffness(p.stiffness, k.h), p.iterations);
    k.k_rest = rods::iteration_stiffness(rods::substep_stiffness(p.rest_stiffness, k.h), p.iterations);
    k.decay = std::exp(-p.damping * k.h);
    const glm::vec3 h_acceleration = k.h * (p.gravity + p.wind);
    k.h_acceleration = {h_acceleration.x, h_acceleration.y, h_acceleration.z};
    k.normal_decay = std::exp(-p.normal_drag * k.h);
    k.tangent_decay = std::exp(-p.tangent_drag * k.h);
    k.half_h = 0.5f * k.h;
    k.two_over_h = 2.0f / k.h;
    k.ftl_over_h = rods::kFollowTheLeaderDamping / k.h;
}

// A vector's cost on each width, relative to one lane of the scalar target: a batch of
// the procedural strands (16 joints, 4 iterations, a collider, 3 views) took 20.5 us a
// vector on avx512, 14.2 on avx2, 13.0 on sse4 and 8.9 on scalar, one thread of the
// project's 2-core Xeon (bench chains --count 8..128 --isa X --threads 1). A batch runs
// on the width that costs least for its lanes in use: one chain, scalar; 2-4, sse4; 5-8,
// avx2; more, avx512. Every width gives the same bits (rods_simd.hpp, "Exactness"), so
// the choice changes the time only.
constexpr simd::VectorCosts kRodVectorCosts{20.5 / 8.9, 14.2 / 8.9, 13.0 / 8.9, 1.0};

class SimdRodBackend final : public RodBackend {
public:
    SimdRodBackend(simd::Isa isa, unsigned threads) : isa_(std::move(isa)), threads_(threads), widths_(simd::isas_up_to(isa_)) {
        for (const simd::Isa& w : widths_) kernels_.push_back(simd::rod_kernels(w.target));
    }

    std::string_view name() const override { return "cpu"; }
    std::string device() const override {
        return std::to_string(threads_) + (threads_ == 1 ? " thread, " : " threads, ") + isa_.name;
    }

    Result<void> load(const rods::RodWorld& world, const rods::RodFrame& initial) override {
        KW_TRY(rods::check_frame(world, initial));
        world_ = &world;
        dt_ = -1.0f;
        templates_.clear();
        for (const rods::ChainTemplate& t : world.templates) templates_.push_back(template_consts(t));

        // Batches: each template's chains in world order, 16 at a time.
        batches_.clear();
        batch_width_.clear();
        std::vector<std::vector<std::uint32_t>> by_template(world.templates.size());
        for (std::uint32_t c = 0; c < world.chains.size(); ++c) by_template[world.chains[c].template_index].push_back(c);
        std::size_t floats = 0, sag_floats = 0;
        lane_of_.assign(world.chains.size(), {});
        for (std::uint32_t t = 0; t < by_template.size(); ++t) {
            const std::vector<std::uint32_t>& chains = by_template[t];
            for (std::size_t first = 0; first < chains.size(); first += kBatchLanes) {
                simd::RodBatch b;
                b.templ = t;
                b.count = static_cast<std::uint32_t>(std::min(kBatchLanes, chains.size() - first));
                for (std::size_t l = 0; l < kBatchLanes; ++l) {
                    b.chain[l] = chains[first + (l < b.count ? l : 0)];
                    b.colliders = std::max(b.colliders, world.chains[b.chain[l]].collider_count);
                }
                for (std::uint32_t l = 0; l < b.count; ++l) lane_of_[b.chain[l]] = {batches_.size(), l};
                batch_width_.push_back(static_cast<std::uint8_t>(simd::cheapest_width(widths_, b.count, kRodVectorCosts)));
                b.offset = floats;
                floats += simd::rod_block_floats(templates_[t].joints);
                b.sag_offset = sag_floats;
                sag_floats += std::size_t{templates_[t].joints} * 3 * kBatchLanes;
                batches_.push_back(b);
            }
        }
        storage_ = hwy::AllocateAligned<float>(std::max<std::size_t>(floats, 1));
        sag_ = hwy::AllocateAligned<float>(std::max<std::size_t>(sag_floats, 1));
        // keyed-examples.md K.6: the keys are measured per chain by engine/rods itself.
        keyed_chains_.clear();
        for (std::uint32_t c = 0; c < world.chains.size(); ++c) {
            if (!world.templ(world.chains[c]).keyed.empty()) keyed_chains_.push_back(c);
        }
        key_states_.assign(world.chains.size(), {});
        for (const std::uint32_t c : keyed_chains_) key_states_[c] = rods::initial_key_state(world, c, initial);
        keyed_.assign(keyed_chains_.empty() ? 0 : world.chains.size() * rods::kMaxKeyedExamples, 0.0f);
        center_chains_.clear();
        for (std::uint32_t c = 0; c < world.chains.size(); ++c) {
            if (world.chains[c].center != rods::kNoCenter) center_chains_.push_back(c);
        }
        centers_ = initial.centers;
        started_ = false;
        split_threads();

        // Every chain at rest on its initial rest shape, by engine/rods itself (as the other
        // backends start), padding lanes as copies of their batch's first chain.
        parallel_for(batches_.size(), threads_, [&](std::size_t begin, std::size_t end) {
            for (std::size_t b = begin; b < end; ++b) {
                const simd::RodBatch& batch = batches_[b];
                rods::ChainState first;
                for (std::size_t l = 0; l < kBatchLanes; ++l) {
                    const std::uint32_t c = batch.chain[l];
                    const rods::RestShape rest = rods::rest_shape(world, c, initial);
                    // Padding lanes copy the first chain's state, settled once.
                    const rods::ChainState s = l < batch.count ? rods::initial_chain_state(world, c, initial) : first;
                    if (l == 0) first = s;
                    put_state(batch, l, s);
                    float* chain = chain_rows(batch);
                    const float view[3] = {rest.view_direction.x, rest.view_direction.y, rest.view_direction.z};
                    for (std::size_t r = 0; r < 3; ++r) chain[(simd::kView + r) * kBatchLanes + l] = view[r];
                    for (std::size_t k = 0; k < kWeightCount; ++k) {
                        chain[(simd::kWeights + k) * kBatchLanes + l] = k < rest.weights.size() ? rest.weights[k] : 0.0f;
                    }
                }
            }
        });
        return {};
    }

    Result<void> step(const rods::RodFrame& frame) override {
        assert(world_ != nullptr && "load() first");
        KW_TRY(rods::check_frame(*world_, frame));
        if (frame.dt != dt_) {
            for (std::size_t t = 0; t < templates_.size(); ++t) {
                const rods::SolverParams& params = world_->templates[t].params;
                set_step(templates_[t].step, params, frame.dt);
                set_step(templates_[t].reduced, rods::reduced_params(params), frame.dt);
            }
            dt_ = frame.dt;
        }
        // Chains with a center frame are carried by its motion first, by engine/rods itself
        // (cpu-reference's step_chain_reference), lane by lane: they are few (a VRM
        // avatar's springs that name a center), and the result keeps the reference's bits.
        parallel_for(center_chains_.size(), threads_, [&](std::size_t begin, std::size_t end) {
            for (std::size_t i = begin; i < end; ++i) {
                const std::uint32_t c = center_chains_[i];
                const std::uint32_t center = world_->chains[c].center;
                rods::ChainState s = state(c);
                rods::follow_center(centers_[center], frame.centers[center], s);
                put_state(batches_[lane_of_[c].first], lane_of_[c].second, s);
            }
        });
        centers_ = frame.centers;
        // Teleports (rods::follow_teleport, which rods::step calls first), by engine/rods
        // itself as the centers above: a chain whose root jumped farther than its
        // template's teleport distance is carried lane by lane (rare: a cut, a respawn),
        // after its center's carry as in the reference; the scan reads one root a chain.
        // The world's first step then starts its chains moving with their roots
        // (rods::start_moving, as rods::step on a chain's first step).
        const bool first = !started_;
        started_ = true;
        // Levels of detail (rods::chain_level, by engine/rods' own function, a few dozen
        // operations a chain), written to each lane's level row for the kernel, padding
        // lanes too (they repeat their batch's first chain).
        const rods::LodView lod = rods::lod_view(world_->lod, frame.camera, frame.full_distance_cap);
        // The posed and hidden levels' rate (rods::chain_rests): which lanes keep their state.
        const bool rate = lod.enabled && lod.lower_rate && frame.number != rods::kNoFrameNumber;
        resting_.assign(rate ? batches_.size() : 0, 0u);
        parallel_for(batches_.size(), threads_, [&](std::size_t begin, std::size_t end) {
            for (std::size_t b = begin; b < end; ++b) {
                const simd::RodBatch& batch = batches_[b];
                float* chain = chain_rows(batch);
                if (world_->lod.enabled) {
                    for (std::size_t l = 0; l < kBatchLanes; ++l) {
                        float& level = chain[simd::kLevel * kBatchLanes + l];
                        float& share = chain[simd::kBlendIn * kBatchLanes + l];
                        const rods::ChainInstance& instance = world_->chains[batch.chain[l]];
                        const glm::vec3 reference = frame.reference[instance.character].position;
                        const auto previous = static_cast<rods::Level>(static_cast<std::uint32_t>(level));
                        const rods::Level next = rods::chain_level(lod, reference, previous);
                        // As cpu_rods.cpp step_chain_reference (a chain with a center frame steps every frame).
                        if (rate && instance.center == rods::kNoCenter &&
                            rods::chain_rests(lod, reference, next, previous,
                                              rods::rate_turn(frame.number, frame.first_character + instance.character))) {
                            chain[simd::kIdle * kBatchLanes + l] += 1.0f;
                            resting_[b] |= 1u << l;
                            continue;
                        }
                        level = static_cast<float>(static_cast<std::uint32_t>(next));
                        share = lod.enabled ? rods::blend_in(world_->lod, next, share, frame.dt) : 1.0f;
                    }
                }
                for (std::size_t l = 0; l < batch.count; ++l) {  // padding lanes' results are unused
                    if (!resting_.empty() && (resting_[b] >> l & 1u) != 0u) continue;
                    const std::uint32_t c = batch.chain[l];
                    const rods::SolverParams& params = world_->templ(world_->chains[c]).params;
                    const glm::vec3 last(chain[(simd::kRootP + 0) * kBatchLanes + l], chain[(simd::kRootP + 1) * kBatchLanes + l],
                                         chain[(simd::kRootP + 2) * kBatchLanes + l]);
                    const bool teleport = rods::teleported(last, frame.roots[c].position, params.teleport_distance);
                    const bool start = first && params.settle_start;
                    if (!teleport && !start) continue;
                    rods::ChainState s = state(c);
                    // A posed step's carry is over the frames it covers (rods::step_posed's follow_teleport).
                    const float carry_dt = !rods::dynamic(static_cast<rods::Level>(s.level))
                                               ? frame.dt * static_cast<float>(s.idle + 1)
                                               : frame.dt;
                    if (teleport) rods::follow_teleport(params, frame.roots[c], carry_dt, s);
                    if (start) rods::start_moving(frame.roots[c], frame.dt, s);
                    put_state(batch, l, s);
                }
            }
        });
        // The keyed weights (rods::measure_keys) of the chains that step, over the frames
        // since their last step (their kIdle row, which the kernel sets to 0 again).
        parallel_for(keyed_chains_.size(), threads_, [&](std::size_t begin, std::size_t end) {
            for (std::size_t i = begin; i < end; ++i) {
                const std::uint32_t c = keyed_chains_[i];
                const auto [b, l] = lane_of_[c];
                if (!resting_.empty() && (resting_[b] >> l & 1u) != 0u) continue;
                const auto frames = static_cast<std::uint32_t>(chain_rows(batches_[b])[simd::kIdle * kBatchLanes + l]) + 1u;
                const rods::KeyedWeights u = rods::measure_keys(*world_, c, frame, key_states_[c], frames);
                std::copy(u.begin(), u.end(), keyed_.begin() + static_cast<std::ptrdiff_t>(c * rods::kMaxKeyedExamples));
            }
        });
        // The air around each chain (rods::chain_air), by engine/rods' own function (a
        // hundred operations a chain with gusts), where any field moves the air; in calm
        // air it is 0 everywhere, which the kernel takes without the rows (same bits).
        const bool moving = moving_air(frame);
        if (moving) {
            air_.resize(world_->chains.size() * 3);
            parallel_for(world_->chains.size(), threads_, [&](std::size_t begin, std::size_t end) {
                for (std::size_t c = begin; c < end; ++c) {
                    const glm::vec3 a = rods::chain_air(*world_, static_cast<std::uint32_t>(c), frame);
                    for (int r = 0; r < 3; ++r) air_[c * 3 + r] = a[r];
                }
            });
        }
        simd::RodStepArgs args{templates_.data(), batches_.data(), storage_.get(), &frame, world_->chains.data(),
                               keyed_.data(), moving ? air_.data() : nullptr, lod.enabled, {}, nullptr, sag_.get()};
        for (std::size_t k = 0; k < args.blend.size(); ++k) {
            args.blend[k] = rods::posed_blend(world_->lod, frame.dt * static_cast<float>(k + 1));
        }
        if (rate) args.resting = resting_.data();
        // With levels of detail a batch's cost follows its lanes' levels: the threads'
        // ranges are split again each frame.
        if (lod.enabled) split_threads(true);
        const std::size_t parts = split_.size() - 1;
        parallel_for(parts, static_cast<unsigned>(parts), [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin; p < end; ++p) {
                // Each run of batches of one width by that width's kernel.
                for (std::size_t from = split_[p]; from < split_[p + 1];) {
                    std::size_t to = from + 1;
                    while (to < split_[p + 1] && batch_width_[to] == batch_width_[from]) ++to;
                    kernels_[batch_width_[from]].step(args, from, to);
                    from = to;
                }
            }
        });
        return {};
    }

    Result<void> read(ChainSnapshot& out) override {
        assert(world_ != nullptr && "load() first");
        const std::size_t count = world_->chains.size();
        out.positions.resize(world_->joint_count);
        out.orientations.resize(world_->joint_count);
        out.rest.resize(world_->joint_count);
        out.view_directions.resize(count);
        out.weights.assign(count * kWeightCount, 0.0f);
        parallel_for(count, threads_, [&](std::size_t begin, std::size_t end) {
            for (std::size_t c = begin; c < end; ++c) {
                const rods::ChainInstance& chain = world_->chains[c];
                const std::size_t b = lane_of_[c].first;  // not a structured binding: lambdas below use l (clang < 16)
                const std::uint32_t l = lane_of_[c].second;
                const float* joints = block(batches_[b]);
                const float* rows = chain_rows(batches_[b]);
                auto at = [&](const float* base, std::size_t row) { return base[row * kBatchLanes + l]; };
                const glm::vec3 root_p(at(rows, simd::kRootP), at(rows, simd::kRootP + 1), at(rows, simd::kRootP + 2));
                const glm::quat root_q(at(rows, simd::kRootQ + 3), at(rows, simd::kRootQ), at(rows, simd::kRootQ + 1),
                                       at(rows, simd::kRootQ + 2));
                out.view_directions[c] = {at(rows, simd::kView), at(rows, simd::kView + 1), at(rows, simd::kView + 2)};
                const std::size_t m = world_->templ(chain).views.size() + world_->templ(chain).keyed.size();
                for (std::size_t k = 0; k <= m; ++k) out.weights[c * kWeightCount + k] = at(rows, simd::kWeights + k);
                for (std::uint32_t i = 0; i < world_->templ(chain).chain.joint_count; ++i) {
                    const std::size_t r = std::size_t{i} * simd::kJointRows;
                    const glm::vec3 x(at(joints, r + simd::kX), at(joints, r + simd::kX + 1), at(joints, r + simd::kX + 2));
                    const glm::vec3 rest(at(joints, r + simd::kRestP), at(joints, r + simd::kRestP + 1), at(joints, r + simd::kRestP + 2));
                    // rods::position(), and cpu-reference's keep(): the rest shape placed by the root.
                    out.positions[chain.joint_begin + i] = root_p + x;
                    out.orientations[chain.joint_begin + i] = glm::quat(at(joints, r + simd::kQ + 3), at(joints, r + simd::kQ),
                                                                        at(joints, r + simd::kQ + 1), at(joints, r + simd::kQ + 2));
                    out.rest[chain.joint_begin + i] = root_p + root_q * rest;
                }
            }
        });
        return {};
    }

    Result<void> read_states(std::vector<rods::ChainState>& out) override {
        assert(world_ != nullptr && "load() first");
        out.resize(world_->chains.size());
        parallel_for(out.size(), threads_, [&](std::size_t begin, std::size_t end) {
            for (std::size_t c = begin; c < end; ++c) out[c] = state(static_cast<std::uint32_t>(c));
        });
        return {};
    }

private:
    float* block(const simd::RodBatch& b) const { return storage_.get() + b.offset; }
    float* chain_rows(const simd::RodBatch& b) const {
        return block(b) + std::size_t{templates_[b.templ].joints} * simd::kJointRows * kBatchLanes;
    }

    // A chain's state to and from its lane.
    void put_state(const simd::RodBatch& b, std::size_t l, const rods::ChainState& s) {
        float* rows = block(b);
        auto put = [&](std::size_t row, float v) { rows[row * kBatchLanes + l] = v; };
        for (std::uint32_t i = 0; i < templates_[b.templ].joints; ++i) {
            const std::size_t r = std::size_t{i} * simd::kJointRows;
            const float joint[simd::kJointRows] = {
                s.x[i].x, s.x[i].y, s.x[i].z, s.v[i].x, s.v[i].y, s.v[i].z, s.q[i].x, s.q[i].y, s.q[i].z, s.q[i].w,
                s.omega[i].x, s.omega[i].y, s.omega[i].z, s.rest_position[i].x, s.rest_position[i].y, s.rest_position[i].z,
                s.rest_orientation[i].x, s.rest_orientation[i].y, s.rest_orientation[i].z, s.rest_orientation[i].w};
            for (std::size_t f = 0; f < simd::kJointRows; ++f) put(r + f, joint[f]);
        }
        float* chain = chain_rows(b);
        const float root[7] = {s.root.position.x, s.root.position.y, s.root.position.z, s.root.rotation.x,
                               s.root.rotation.y, s.root.rotation.z, s.root.rotation.w};
        for (std::size_t f = 0; f < 7; ++f) chain[(simd::kRootP + f) * kBatchLanes + l] = root[f];
        chain[simd::kLevel * kBatchLanes + l] = static_cast<float>(s.level);
        chain[simd::kBlendIn * kBatchLanes + l] = s.blend_in;
        chain[simd::kIdle * kBatchLanes + l] = static_cast<float>(s.idle);
        float* sag = sag_.get() + b.sag_offset;
        for (std::uint32_t i = 0; i < templates_[b.templ].joints; ++i) {
            for (std::size_t r = 0; r < 3; ++r) sag[(3 * i + r) * kBatchLanes + l] = s.sag[i][static_cast<int>(r)];
        }
    }

    rods::ChainState state(std::uint32_t c) const {
        const std::size_t b = lane_of_[c].first;  // not a structured binding: lambdas below use l (clang < 16)
        const std::uint32_t l = lane_of_[c].second;
        const simd::RodBatch& batch = batches_[b];
        const float* rows = block(batch);
        auto get = [&](std::size_t row) { return rows[row * kBatchLanes + l]; };
        rods::ChainState s;
        for (std::uint32_t i = 0; i < templates_[batch.templ].joints; ++i) {
            const std::size_t r = std::size_t{i} * simd::kJointRows;
            s.x[i] = {get(r + simd::kX), get(r + simd::kX + 1), get(r + simd::kX + 2)};
            s.v[i] = {get(r + simd::kV), get(r + simd::kV + 1), get(r + simd::kV + 2)};
            s.q[i] = glm::quat(get(r + simd::kQ + 3), get(r + simd::kQ), get(r + simd::kQ + 1), get(r + simd::kQ + 2));
            s.omega[i] = {get(r + simd::kOmega), get(r + simd::kOmega + 1), get(r + simd::kOmega + 2)};
            s.rest_position[i] = {get(r + simd::kRestP), get(r + simd::kRestP + 1), get(r + simd::kRestP + 2)};
            s.rest_orientation[i] = glm::quat(get(r + simd::kRestO + 3), get(r + simd::kRestO), get(r + simd::kRestO + 1),
                                              get(r + simd::kRestO + 2));
        }
        const float* chain = chain_rows(batch);
        auto at = [&](std::size_t row) { return chain[row * kBatchLanes + l]; };
        s.root.position = {at(simd::kRootP), at(simd::kRootP + 1), at(simd::kRootP + 2)};
        s.root.rotation = glm::quat(at(simd::kRootQ + 3), at(simd::kRootQ), at(simd::kRootQ + 1), at(simd::kRootQ + 2));
        s.level = static_cast<std::uint32_t>(at(simd::kLevel));
        s.blend_in = at(simd::kBlendIn);
        s.idle = static_cast<std::uint32_t>(at(simd::kIdle));
        const float* sag = sag_.get() + batch.sag_offset;
        for (std::uint32_t i = 0; i < templates_[batch.templ].joints; ++i) {
            s.sag[i] = {sag[(3 * i) * kBatchLanes + l], sag[(3 * i + 1) * kBatchLanes + l], sag[(3 * i + 2) * kBatchLanes + l]};
        }
        if (const std::uint32_t center = world_->chains[c].center; center != rods::kNoCenter) s.center = centers_[center];
        s.started = started_;
        return s;
    }

    // Contiguous batch ranges of about equal cost, one per thread: a batch's work grows
    // with its joints times its projection work (iterations and colliders) and its
    // vectors (lanes in use, rounded up to whole vectors of the instruction set).
    // `levels`: from the lanes' levels of detail (a vector of lanes none of which is full
    // or reduced costs its posed update only, about 2 units a joint; one with reduced lanes
    // adds their step, and one with both adds both).
    void split_threads(bool levels = false) {
        std::vector<double> cost(batches_.size());
        for (std::size_t b = 0; b < batches_.size(); ++b) {
            const simd::RodBatch& batch = batches_[b];
            const simd::RodTemplateConsts& t = templates_[batch.templ];
            const float* chain = chain_rows(batch);
            double vectors = 0.0, full = 0.0, reduced = 0.0;
            // A batch whose every lane keeps its state is not stepped.
            if (levels && !resting_.empty() && resting_[b] == (1u << kBatchLanes) - 1u) {
                cost[b] = 0.0;
                continue;
            }
            const unsigned lanes = widths_[batch_width_[b]].lanes;
            const double weight = kRodVectorCosts.of(lanes);
            for (std::size_t off = 0; off < batch.count; off += lanes) {
                vectors += weight;
                bool any_full = !levels, any_reduced = false;
                for (std::size_t l = off; l < std::min<std::size_t>(off + lanes, kBatchLanes); ++l) {
                    const float level = chain[simd::kLevel * kBatchLanes + l];
                    any_full = any_full || level == 0.0f;
                    any_reduced = any_reduced || (levels && level == static_cast<float>(rods::Level::Reduced));
                }
                if (any_full) full += weight;
                if (any_reduced) reduced += weight;
            }
            const double per_vector = t.joints * (4.0 + batch.colliders);
            const double reduced_share = static_cast<double>(t.reduced.substeps) / static_cast<double>(t.step.substeps);
            cost[b] = vectors * t.joints * 2.0 +
                      per_vector * (full * t.step.iterations + reduced * t.reduced.iterations * reduced_share);
        }
        const double total = std::accumulate(cost.begin(), cost.end(), 0.0);
        const std::size_t parts = std::max<std::size_t>(1, std::min<std::size_t>(threads_, batches_.size()));
        split_.assign(parts + 1, batches_.size());
        split_[0] = 0;
        double done = 0.0;
        std::size_t p = 1;
        for (std::size_t b = 0; b < batches_.size() && p < parts; ++b) {
            done += cost[b];
            while (p < parts && done >= total * static_cast<double>(p) / static_cast<double>(parts)) split_[p++] = b + 1;
        }
    }

    simd::Isa isa_;
    unsigned threads_;
    std::vector<simd::Isa> widths_;           // isa_ and the narrower ones this machine runs (simd::isas_up_to)
    std::vector<simd::RodKernels> kernels_;   // per width
    std::vector<std::uint8_t> batch_width_;   // per batch, its width (simd::cheapest_width of its lanes in use)
    const rods::RodWorld* world_ = nullptr;
    float dt_ = -1.0f;
    std::vector<simd::RodTemplateConsts> templates_;
    std::vector<simd::RodBatch> batches_;
    std::vector<std::pair<std::size_t, std::uint32_t>> lane_of_;  // chain -> (batch, lane)
    std::vector<std::size_t> split_;                              // thread p: batches [split_[p], split_[p + 1])
    std::vector<std::uint32_t> resting_;                          // per batch, its lanes that keep their state (RodStepArgs::resting)
    std::vector<std::uint32_t> keyed_chains_;                     // the chains with keyed examples
    std::vector<rods::KeyState> key_states_;                      // per chain (keyed ones only used)
    std::vector<float> keyed_;                                    // per chain, kMaxKeyedExamples raw weights
    std::vector<float> air_;                                      // per chain, the air's velocity (3 floats)
    std::vector<std::uint32_t> center_chains_;                    // the chains with a center frame
    bool started_ = false;  // whether a step has run since load()
    std::vector<rods::Transform> centers_;                        // the last frame's center frames (RodFrame::centers)
    hwy::AlignedFreeUniquePtr<float[]> storage_;
    hwy::AlignedFreeUniquePtr<float[]> sag_;  // per batch (RodBatch::sag_offset): 3 rows a joint
};

}  // namespace

std::unique_ptr<RodBackend> new_simd_rod_backend(simd::Isa isa, unsigned threads) {
    return std::make_unique<SimdRodBackend>(std::move(isa), threads);
}

}  // namespace kodawari
