// A room's collision world: posing, ball dynamics (stepBall, common/deform/prop.hpp),
// Step 1 (buildInteractions) and the snapshot's world parts (proto/WIRE.md §3.7-3.8).
#include "server/core/room_world.hpp"

#include <algorithm>
#include <cmath>

namespace vistel::server {
namespace {

constexpr double kMaxStep = 0.1;  // seconds: a stalled room does not fling its balls

bool insideWorld(const BallState& b, const WorldSettings& s) {
  const glm::vec3& p = b.position;
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) &&
         std::abs(p.x) <= s.extent_m && std::abs(p.z) <= s.extent_m &&
         p.y >= s.floor_height_m - 1.0f && p.y <= s.floor_height_m + s.extent_m;
}

}  // namespace

RoomWorld::RoomWorld(const WorldSettings& settings) : settings_(settings) {
  settings_.max_parts = std::clamp(settings_.max_parts, 1, wire::kMaxInteractionParts);
}

// ---------------------------------------------------------------- members

RoomWorld::MemberBody* RoomWorld::findMember(MemberId id) {
  for (MemberBody& m : members_) {
    if (m.id == id) return &m;
  }
  return nullptr;
}

void RoomWorld::prepareMember(MemberBody& m) {
  m.has_record = false;
  m.dirty = true;
  m.posed_once = false;
  m.sweep.reset();
  if (!m.model) return;
  const auto n = static_cast<std::size_t>(m.model->skeleton.jointCount());
  m.posture = restPosture(m.model->skeleton);
  m.joint_model.assign(n, glm::mat4(1.0f));
  m.skin.assign(n, glm::mat4(1.0f));
}

void RoomWorld::addMember(MemberId id, const SeatPlacement& seat,
                          std::shared_ptr<const CollisionModel> model) {
  if (findMember(id) != nullptr) return;
  MemberBody& m = members_.emplace_back();
  m.id = id;
  m.placement = seatTransform(seat);
  m.model = std::move(model);
  prepareMember(m);
}

void RoomWorld::setModel(MemberId id, std::shared_ptr<const CollisionModel> model) {
  MemberBody* m = findMember(id);
  if (m == nullptr) return;
  m->model = std::move(model);
  prepareMember(*m);
}

void RoomWorld::removeMember(MemberId id) {
  std::erase_if(members_, [&](const MemberBody& m) { return m.id == id; });
}

void RoomWorld::setPosture(MemberId id, const wire::PostureRecord& record) {
  MemberBody* m = findMember(id);
  if (m == nullptr || !m->model || record.joint_count != m->model->skeleton.jointCount()) return;
  m->record = record;
  m->has_record = true;
  m->dirty = true;
}

void RoomWorld::poseMemberSkeleton(MemberBody& m) {
  if (!m.dirty || !m.model) return;
  // Newest posture (or rest) -> model-space joints -> skinning matrices carried into the room.
  if (m.has_record) wire::decodePostureRecord(m.record, 0.0, m.posture);
  const Skeleton& skeleton = m.model->skeleton;
  vistel::poseSkeleton(skeleton, m.posture, m.joint_model);
  skinningMatrices(skeleton, m.joint_model, m.skin);
  for (glm::mat4& xf : m.skin) xf = m.placement * xf;
  m.dirty = false;
}

std::optional<glm::vec3> RoomWorld::spawnPointAbove(MemberId id) {
  MemberBody* m = findMember(id);
  if (m == nullptr || !m->model) return std::nullopt;
  poseMemberSkeleton(*m);
  const auto head = static_cast<std::size_t>(m->model->head_joint);
  const glm::vec3 head_room(m->placement * m->joint_model[head][3]);
  const glm::vec3 forward(m->placement * glm::vec4(0.0f, 0.0f, 1.0f, 0.0f));
  return head_room + glm::vec3(0.0f, settings_.spawn_height_m, 0.0f) +
         settings_.spawn_forward_m * forward;
}

std::optional<glm::vec3> RoomWorld::headPosition(MemberId id) {
  MemberBody* m = findMember(id);
  if (m == nullptr || !m->model) return std::nullopt;
  poseMemberSkeleton(*m);
  const auto head = static_cast<std::size_t>(m->model->head_joint);
  return glm::vec3(m->placement * m->joint_model[head][3]);
}

// ---------------------------------------------------------------- props

bool RoomWorld::addProp(PropId id, const PropSpec& spec, const glm::vec3& position,
                        const glm::vec3& velocity) {
  for (const PropBody& p : props_) {
    if (p.id == id) return false;
  }
  if (!validatePropSpec(spec)) return false;
  auto set = makeBallPrimitives(spec.ball);
  if (!set) return false;
  const BallState state = ballState(spec, position, velocity);
  if (!validateBallState(state)) return false;
  PropBody& p = props_.emplace_back();
  p.id = id;
  p.spec = spec;
  p.set = std::move(*set);
  p.state = state;
  p.start_position = position;
  p.start_velocity = velocity;
  return true;
}

void RoomWorld::removeProp(PropId id) {
  std::erase_if(props_, [&](const PropBody& p) { return p.id == id; });
}

const BallState* RoomWorld::propState(PropId id) const {
  for (const PropBody& p : props_) {
    if (p.id == id) return &p.state;
  }
  return nullptr;
}

void RoomWorld::poseProp(PropBody& p, int slot) {
  const glm::mat4 placement = ballPlacement(p.state);
  posePrimitives(p.set, std::span<const glm::mat4>(&placement, 1), p.posed[slot]);
}

// ---------------------------------------------------------------- motion margins

void SweptBounds::update(double t, const PosedPrimitives& posed, float window, float lead,
                         PosedPrimitives& swept) {
  const std::size_t n = posed.items.size();
  if (n != prims_) {
    prims_ = n;
    boxes_.assign(static_cast<std::size_t>(kCapacity) * n, Bounds{});
    count_ = 0;
    head_ = 0;
  }
  Bounds* const now = boxes_.data() + static_cast<std::size_t>(head_) * n;
  for (std::size_t i = 0; i < n; ++i) now[i] = posed.items[i].bounds;
  times_[static_cast<std::size_t>(head_)] = t;
  const int newest = head_;
  head_ = (head_ + 1) % kCapacity;
  count_ = std::min(count_ + 1, kCapacity);
  swept = posed;  // same sizes after the first tick: no allocation
  swept.bounds = Bounds{glm::vec3(INFINITY), glm::vec3(-INFINITY)};
  for (std::size_t i = 0; i < n; ++i) {
    // The farthest a corner moved within the window, and over what span.
    float moved = 0.0f;
    double span = 0.0;
    for (int k = 1; k < count_; ++k) {
      const int slot = (newest - k + kCapacity) % kCapacity;
      const double age = t - times_[static_cast<std::size_t>(slot)];
      if (age > static_cast<double>(window) + 1e-9) break;
      const Bounds& then = boxes_[static_cast<std::size_t>(slot) * n + i];
      moved =
          std::max({moved, glm::length(now[i].min - then.min), glm::length(now[i].max - then.max)});
      span = age;
    }
    const float speed = span > 0.0 ? moved / static_cast<float>(span) : 0.0f;
    const float margin = moved + speed * lead;
    PosedPrimitive& q = swept.items[i];
    q.reach += margin;
    q.bounds.min -= glm::vec3(margin);
    q.bounds.max += glm::vec3(margin);
    swept.bounds.min = glm::min(swept.bounds.min, q.bounds.min);
    swept.bounds.max = glm::max(swept.bounds.max, q.bounds.max);
  }
  if (n == 0) swept.bounds = posed.bounds;
}

// ---------------------------------------------------------------- the tick

void RoomWorld::step(double dt_in) {
  const float dt = static_cast<float>(std::clamp(dt_in, 1e-4, kMaxStep));
  slot_ ^= 1;
  const int prev = slot_ ^ 1;

  // 1. Pose every colliding member and every prop; list the bodies with last tick's poses
  //    beside (a body new this tick counts as still).
  bodies_.clear();
  views_.clear();
  previous_views_.clear();
  for (MemberBody& m : members_) {
    if (!m.model || !m.model->collides) continue;
    poseMemberSkeleton(m);
    posePrimitives(m.model->primitives, m.skin, m.posed[slot_]);
    if (!m.posed_once) m.posed[prev] = m.posed[slot_];
    m.posed_once = true;
    bodies_.push_back({false, m.id.value});
    views_.push_back({&m.model->graph, &m.posed[slot_]});
    previous_views_.push_back({&m.model->graph, &m.posed[prev]});
  }
  const std::size_t first_prop = views_.size();
  for (PropBody& p : props_) {
    poseProp(p, slot_);
    if (!p.posed_once) p.posed[prev] = p.posed[slot_];
    p.posed_once = true;
    bodies_.push_back({true, p.id.value});
    views_.push_back({nullptr, &p.posed[slot_]});
    previous_views_.push_back({nullptr, &p.posed[prev]});
  }

  // 2. Step each ball against everything else as posed at the start of the tick; balls
  //    that leave the world or fail are put back where they started.
  BallStepOptions options;
  options.gravity = glm::vec3(0.0f, -settings_.gravity_mps2, 0.0f);
  options.floor_height = settings_.floor_height_m;
  options.previous = previous_views_;
  options.previous_interval = dt;
  for (std::size_t i = 0; i < props_.size(); ++i) {
    PropBody& p = props_[i];
    options.skip_body = static_cast<int>(first_prop + i);
    const BallStepReport report = stepBall(p.state, views_, dt, options);
    if (!report.valid || !insideWorld(p.state, settings_)) {
      p.state.position = p.start_position;
      p.state.velocity = p.start_velocity;
      ++prop_resets_;
    }
  }
  for (PropBody& p : props_) poseProp(p, slot_);

  // 3. Step 1 across and within bodies, over the primitives swollen by their motion.
  time_ += dt;
  swept_views_.clear();
  const float window = std::max(settings_.contact_window_s, 0.0f);
  const float lead = std::max(settings_.contact_lead_s, 0.0f);
  for (MemberBody& m : members_) {
    if (!m.model || !m.model->collides) continue;
    m.sweep.update(time_, m.posed[slot_], window, lead, m.swept);
    swept_views_.push_back({&m.model->graph, &m.swept});
  }
  for (PropBody& p : props_) {
    p.sweep.update(time_, p.posed[slot_], window, lead, p.swept);
    swept_views_.push_back({nullptr, &p.swept});
  }
  buildInteractions(swept_views_, scratch_, list_, settings_.send_self_contact);

  // 4. The snapshot's world parts.
  prop_records_.clear();
  for (const PropBody& p : props_) {
    prop_records_.push_back(wire::encodePropState(p.id.value, p.state.position, p.state.velocity));
  }
  writeParts();
}

void RoomWorld::writeParts() {
  const auto& pairs = list_.pairs;
  const std::size_t body_count = bodies_.size();
  if (body_stamp_.size() < body_count) {
    body_stamp_.resize(body_count, 0);
    local_index_.resize(body_count, 0);
  }

  // Priority: pairs between bodies, then self-contact (dropped first when truncating;
  // not sent at all unless asked: every client computes its bodies' own).
  order_.clear();
  for (std::uint32_t i = 0; i < pairs.size(); ++i) {
    if (pairs[i].body_a != pairs[i].body_b) order_.push_back(i);
  }
  for (std::uint32_t i = 0; settings_.send_self_contact && i < pairs.size(); ++i) {
    if (pairs[i].body_a == pairs[i].body_b) order_.push_back(i);
  }

  // Split greedily: each part's section (its own body table and the pairs) must fit the
  // datagram beside the header (and, in part 0, the prop states).
  const std::size_t props_bytes = prop_records_.size() * wire::kPropStateBytes;
  const std::size_t room = wire::kMaxPlainDatagramBytes - wire::kSnapshotHeaderBytes;
  part_ends_.clear();
  truncated_ = false;
  int bodies_in_part = 0;
  std::size_t pairs_in_part = 0;
  ++epoch_;
  const auto mark = [&](std::uint16_t b) {
    if (body_stamp_[b] == epoch_) return 0;
    body_stamp_[b] = epoch_;
    return 1;
  };
  for (std::size_t k = 0; k < order_.size(); ++k) {
    const Interaction& pair = pairs[order_[k]];
    const std::size_t budget = part_ends_.empty() ? room - props_bytes : room;
    const int fresh = (body_stamp_[pair.body_a] != epoch_ ? 1 : 0) +
                      (pair.body_b != pair.body_a && body_stamp_[pair.body_b] != epoch_ ? 1 : 0);
    const int bodies = bodies_in_part + fresh;
    if (bodies > wire::kMaxSectionBodies ||
        wire::interactionSectionBytes(bodies, pairs_in_part + 1) > budget) {
      // Close this part; start the next unless that would pass the limit.
      part_ends_.push_back(static_cast<std::uint32_t>(k));
      if (static_cast<int>(part_ends_.size()) >= settings_.max_parts) {
        truncated_ = true;
        break;
      }
      ++epoch_;
      bodies_in_part = 0;
      pairs_in_part = 0;
    }
    bodies_in_part += mark(pair.body_a) + mark(pair.body_b);
    ++pairs_in_part;
  }
  if (!truncated_) part_ends_.push_back(static_cast<std::uint32_t>(order_.size()));

  // Write each part: its body table in world order (members, then props), its pairs.
  part_count_ = part_ends_.size();
  if (parts_.size() < part_count_) parts_.resize(part_count_);
  std::uint32_t begin = 0;
  for (std::size_t part = 0; part < part_count_; ++part) {
    const std::uint32_t end = part_ends_[part];
    ++epoch_;
    for (std::uint32_t k = begin; k < end; ++k) {
      mark(pairs[order_[k]].body_a);
      mark(pairs[order_[k]].body_b);
    }
    section_.clear();
    section_.flags = static_cast<std::uint8_t>(
        (truncated_ ? wire::kInteractionsTruncated : 0) |
        (settings_.send_self_contact ? 0 : wire::kInteractionsSelfOmitted));
    for (std::size_t b = 0; b < body_count; ++b) {
      if (body_stamp_[b] != epoch_) continue;
      local_index_[b] = static_cast<std::uint8_t>(section_.bodyCount());
      (bodies_[b].is_prop ? section_.prop_ids : section_.member_ids).push_back(bodies_[b].id);
    }
    for (std::uint32_t k = begin; k < end; ++k) {
      const Interaction& p = pairs[order_[k]];
      section_.pairs.push_back(
          {local_index_[p.body_a], p.prim_a, local_index_[p.body_b], p.prim_b});
    }
    WorldPart& out = parts_[part];
    out.bytes.clear();
    out.prop_count = part == 0 ? static_cast<std::uint8_t>(prop_records_.size()) : 0;
    wire::writeSnapshotWorld(part == 0 ? std::span<const wire::PropStateRecord>(prop_records_)
                                       : std::span<const wire::PropStateRecord>(),
                             &section_, out.bytes);
    begin = end;
  }
}

}  // namespace vistel::server
