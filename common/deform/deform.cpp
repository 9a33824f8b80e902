// Steps 2 and 3 of the deformable component (see deform.hpp), the driver: Gascuel 1993, "An
// implicit formulation for precise contact modeling between flexible solids" (per-vertex
// root-finding onto F = T with penetration and propagation terms, relative deformability,
// elastic memory) and Vaillant et al. 2013, "Implicit skinning" (tangential relaxation with a
// final projection), one named call per step.
#include "common/deform/deform.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "common/deform/collision_terms.hpp"
#include "common/deform/contact_forces.hpp"
#include "common/deform/deform_scratch.hpp"
#include "common/deform/face_orientation.hpp"
#include "common/deform/relaxation.hpp"
#include "common/deform/vertex_solve.hpp"

namespace vistel {
namespace {

// Wall time per phase (DeformOptions::time_phases): lap(t) adds the time since the last lap.
class PhaseClock {
 public:
  explicit PhaseClock(bool on) : on_(on), mark_(on ? Clock::now() : Clock::time_point()) {}
  void lap(double& phase) {
    if (!on_) return;
    const Clock::time_point now = Clock::now();
    phase += std::chrono::duration<double>(now - mark_).count();
    mark_ = now;
  }

 private:
  using Clock = std::chrono::steady_clock;
  bool on_;
  Clock::time_point mark_;
};

// Setup: the colliders of this body per own primitive, the own fields' lanes (the fast way
// only) and the chunks' counters.
void setupFrame(DeformFrame& fr, const InteractionList& interactions) {
  DeformScratch& sc = *fr.sc;
  buildColliders(fr, interactions);
  if (!fr.opt->reference) packLaneSets(fr);
  const int chunks = chunkCount(fr);
  if (sc.chunk_counters.size() < static_cast<std::size_t>(chunks)) {
    sc.chunk_counters.resize(static_cast<std::size_t>(chunks));
  }
  for (int c = 0; c < chunks; ++c)
    sc.chunk_counters[static_cast<std::size_t>(c)] = DeformCounters{};
}

// Pass A: rigid-pose penetrations and collision candidates (only vertices with candidates do
// any work), then the move bound's per-frame parts (see moveAllowance).
void findPenetrations(DeformFrame& fr, TaskPool* pool) {
  DeformState& st = *fr.st;
  DeformScratch& sc = *fr.sc;
  if (sc.colliders.empty()) {
    std::fill(st.depth.begin(), st.depth.end(), 0.0f);
    std::fill(st.pressure.begin(), st.pressure.end(), 0.0f);
    std::fill(sc.cand_count.begin(), sc.cand_count.end(), std::uint8_t{0});
  } else if (fr.opt->reference) {
    auto pass_a = [&](int c) {
      const auto [b, e] = chunkRange(fr, c);
      passPenetrationReference(fr, b, e);
    };
    parallelFor(pool, chunkCount(fr), pass_a);
  } else {
    const int npatch = static_cast<int>(sc.patch_offsets.size()) - 1;
    const int patch_tasks = (npatch + kPatchesPerTask - 1) / kPatchesPerTask;
    auto pass_a = [&](int t) {
      passPenetration(fr, t * kPatchesPerTask, std::min(npatch, (t + 1) * kPatchesPerTask));
    };
    parallelFor(pool, patch_tasks, pass_a);
  }
  if (fr.opt->move_margin >= 0.0f &&
      fr.in->rest_positions.size() == static_cast<std::size_t>(fr.nvert)) {
    for (std::size_t i = 0; i < fr.posed->items.size(); ++i)
      sc.prim_to_world[i] = glm::inverse(fr.posed->items[i].to_bind);
    const float deepest =
        sc.colliders.empty() ? 0.0f : *std::max_element(st.depth.begin(), st.depth.end());
    sc.bulge_allowance = bulgeAllowance(fr.model->primitives.propagation_amplitude, deepest);
  }
}

// Pass B: Step 2 proper, chunk by chunk.
void solveVertices(DeformFrame& fr, TaskPool* pool) {
  DeformScratch& sc = *fr.sc;
  std::fill(sc.dirty.begin(), sc.dirty.end(), std::uint8_t{0});
  auto pass_b = [&](int c) {
    const auto [b, e] = chunkRange(fr, c);
    passSolve(fr, b, e, sc.chunk_counters[static_cast<std::size_t>(c)]);
  };
  parallelFor(pool, chunkCount(fr), pass_b);
}

// The chunks' counters, reduced in chunk order.
DeformCounters totalCounters(const DeformFrame& fr) {
  DeformCounters total;
  for (int c = 0; c < chunkCount(fr); ++c) {
    const DeformCounters& k = fr.sc->chunk_counters[static_cast<std::size_t>(c)];
    total.evaluations += k.evaluations;
    total.iterations += k.iterations;
    total.relax_iterations += k.relax_iterations;
    total.iterating_vertices += k.iterating_vertices;
    total.unsolved_vertices += k.unsolved_vertices;
    total.held_vertices += k.held_vertices;
    total.gradient_vertices += k.gradient_vertices;
    total.contact_vertices += k.contact_vertices;
    total.candidate_overflow += k.candidate_overflow;
    total.candidate_vertices += k.candidate_vertices;
    total.rigid_vertices += k.rigid_vertices;
    total.relaxed_vertices += k.relaxed_vertices;
    total.max_offset = std::max(total.max_offset, k.max_offset);
  }
  return total;
}

DeformFrame frameOf(const ImplicitModel& model, std::span<const BodyView> bodies, int self,
                    const DeformInput& in, const DeformState& st, const DeformOptions& opt) {
  DeformFrame fr;
  fr.model = &model;
  fr.bodies = bodies;
  fr.self = self;
  fr.in = &in;
  fr.st = const_cast<DeformState*>(&st);  // written only by deformSkin's passes
  fr.sc = st.scratch.get();
  fr.opt = &opt;
  fr.posed = bodies[static_cast<std::size_t>(self)].posed;
  fr.nvert = model.calibration.vertexCount();
  fr.chunk = std::max(opt.chunk_size, 16);
  return fr;
}

}  // namespace

DeformState::DeformState() : scratch(std::make_unique<DeformScratch>()) {}
DeformState::~DeformState() = default;
DeformState::DeformState(const DeformState& other)
    : positions(other.positions),
      normals(other.normals),
      offset(other.offset),
      free_offset(other.free_offset),
      memory(other.memory),
      contact_body(other.contact_body),
      pressure(other.pressure),
      depth(other.depth),
      flags(other.flags),
      contacts(other.contacts),
      counters(other.counters),
      time(other.time),
      started(other.started),
      scratch(std::make_unique<DeformScratch>(other.scratch != nullptr ? *other.scratch
                                                                       : DeformScratch{})) {}
DeformState& DeformState::operator=(const DeformState& other) {
  if (this != &other) *this = DeformState(other);
  return *this;
}
DeformState::DeformState(DeformState&& other) noexcept = default;
DeformState& DeformState::operator=(DeformState&& other) noexcept = default;

Status initDeformState(const ImplicitModel& model, std::span<const std::uint32_t> indices,
                       DeformState& st) {
  const auto nv = static_cast<std::size_t>(model.calibration.vertexCount());
  if (indices.size() % 3 != 0)
    return fail("deform state: index count {} not a multiple of 3", indices.size());
  for (std::size_t i = 0; i < indices.size(); ++i) {
    if (indices[i] >= nv) return fail("deform state: index {} = {} out of range", i, indices[i]);
  }
  st.positions.assign(nv, glm::vec3(0.0f));
  st.normals.assign(nv, glm::vec3(0.0f));
  st.offset.assign(nv, 0.0f);
  st.free_offset.assign(nv, 0.0f);
  st.memory.assign(nv, 0.0f);
  st.contact_body.assign(nv, -1);
  st.pressure.assign(nv, 0.0f);
  st.depth.assign(nv, 0.0f);
  st.flags.assign(nv, 0);
  st.contacts.clear();
  st.contacts.reserve(64);
  st.counters = {};
  st.time = 0.0;
  st.started = false;
  if (st.scratch == nullptr) st.scratch = std::make_unique<DeformScratch>();
  initDeformScratch(model, indices, *st.scratch);
  return {};
}

void deformSkin(const ImplicitModel& model, std::span<const BodyView> bodies, int self,
                const InteractionList& interactions, const DeformInput& in, DeformState& st,
                const DeformOptions& opt, TaskPool* pool) {
  DeformFrame fr = frameOf(model, bodies, self, in, st, opt);
  fr.dt = st.started ? static_cast<float>(std::max(in.time - st.time, 0.0)) : 0.0f;
  st.time = in.time;
  st.started = true;
  DeformPhaseTimes times;
  PhaseClock clock(opt.time_phases);

  setupFrame(fr, interactions);
  findPenetrations(fr, pool);  // pass A
  clock.lap(times.penetration);
  solveVertices(fr, pool);  // pass B
  clock.lap(times.solve);
  relaxJointVertices(fr, pool);
  clock.lap(times.relax);
  const int smoothed = opt.smooth_passes > 0 ? smoothCorrections(fr) : 0;
  boundRelaxedMoves(fr);
  const int reoriented = restoreFaceOrientation(fr);
  clock.lap(times.smooth);
  skinNormals(fr, pool);  // Step 3
  clock.lap(times.normals);
  passContacts(fr);
  clock.lap(times.contacts);

  st.counters = totalCounters(fr);
  st.counters.smoothed_vertices = smoothed;
  st.counters.reoriented_vertices = reoriented;
  st.counters.phase_seconds = times;
}

bool carryDeformState(const DeformState& from, DeformState& to) {
  if (from.offset.size() != to.offset.size() || from.memory.size() != to.memory.size() ||
      from.free_offset.size() != to.free_offset.size()) {
    return false;
  }
  to.offset = from.offset;
  to.free_offset = from.free_offset;
  to.memory = from.memory;
  to.time = from.time;
  to.started = from.started;
  return true;
}

bool adoptElasticMemory(const ImplicitModel& model, std::span<const float> memory,
                        DeformState& state, float age_s) {
  const std::size_t nv = state.memory.size();
  if (memory.size() != nv || model.calibration.prims.size() != nv) return false;
  if (!(age_s >= 0.0f) || !std::isfinite(age_s)) return false;
  for (const float m : memory) {
    if (!(m <= 0.0f) || !std::isfinite(m)) return false;
  }
  for (std::size_t v = 0; v < nv; ++v) {
    const std::int16_t p0 = model.calibration.prims[v][0];
    if (p0 < 0) {
      state.memory[v] = 0.0f;
      continue;
    }
    const Primitive& own = model.primitives.items[static_cast<std::size_t>(p0)];
    state.memory[v] = own.elasticity == Elasticity::kElastic ? 0.0f
                      : age_s > 0.0f ? updateElasticMemory(own.elasticity, memory[v], 0.0f, age_s,
                                                           own.time_constant)
                                     : memory[v];
  }
  return true;
}

float vertexFunction(const ImplicitModel& model, std::span<const BodyView> bodies, int self,
                     const DeformInput& input, const DeformState& state,
                     const DeformOptions& options, int v, const glm::vec3& p, glm::vec3* gradient) {
  const DeformFrame fr = frameOf(model, bodies, self, input, state, options);
  VertexProblem vp;
  gatherVertexProblem(fr, v, true, vp);  // only reads the state
  vp.lanes = nullptr;  // the own fields from `bodies` themselves (the same values)
  for (int i = 0; i < vp.ncand; ++i) vp.cand[i].lane = -1;
  glm::vec3 grad;
  const float g = evaluate(vp, p, grad);
  if (gradient != nullptr) *gradient = grad;
  return g;
}

}  // namespace vistel
