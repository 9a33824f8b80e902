// The collision world of one room (DESIGN.md §1, §6): every member's collision model
// (skeleton, primitives, combination graph) posed from its newest posture at its seat,
// the room's props, and per tick
//   1. pose every member's primitives (placement x skinning matrices),
//   2. step every ball by the fields' reaction of everything else (stepBall: gravity,
//      floor, restitution; the surfaces' velocities from the previous tick's poses),
//   3. Step 1 across bodies, and within them when send_self_contact (buildInteractions),
//      over each primitive swollen by how far it moved in the last contact_window_s and
//      will move in the next contact_lead_s (a client draws remote members behind the
//      server's newest postures and its own ahead: the list must hold the pairs that touch
//      in what it draws, see SweptBounds),
//   4. serialize the snapshot's world parts once for every recipient: the prop states and
//      the interaction list, split over at most max_parts datagrams (pairs between bodies
//      first; self-contact pairs are dropped first when the list does not fit, and the
//      parts say so).
// Pure and single-threaded (the room's strand); allocation-free per tick once every
// buffer has grown to the room's size.
//
// Bodies of Step 1, in this order: members that have an implicit model (in the order they
// were added), then props (in the order they were spawned).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "common/anim/posture.hpp"
#include "common/deform/interactions.hpp"
#include "common/deform/posed_primitives.hpp"
#include "common/deform/prop.hpp"
#include "common/scene/seat_layout.hpp"
#include "common/wire/packets.hpp"
#include "server/core/collision_model.hpp"
#include "server/core/handles.hpp"
#include "server/core/props.hpp"

namespace vistel::server {

struct WorldSettings {
  float gravity_mps2 = 9.81f;      // along -Y
  float floor_height_m = 0.0f;     // rigid floor plane
  float extent_m = 20.0f;          // a ball beyond |x|, |z| or this height is put back
  int max_parts = 4;               // interaction datagrams per tick (1..32)
  bool send_self_contact = false;  // compute and send self-contact pairs too (else clients
                                   // compute them; the world's list has none)
  float spawn_height_m = 0.6f;     // spawnPointAbove: this far above the head joint
  float spawn_forward_m = 0.03f;   // ... and this far in front of it (so it rolls off)
  float contact_window_s = 0.15f;  // Step 1 covers where each primitive was this far back
                                   // (clients draw remote members a playback delay behind,
                                   // 0.1 s by default, plus a tick or two); 0: newest only
  float contact_lead_s = 0.05f;    // ... and where its recent motion takes it this far ahead
                                   // (a client draws its own avatar ahead of the server)
};

// The motion margins of one body's primitives: a ring of their boxes over the last ticks
// (at most kCapacity), and from it how far each primitive moved. Allocation-free once
// sized for the body's primitives.
class SweptBounds {
 public:
  static constexpr int kCapacity = 32;  // ticks remembered (0.53 s at 60 Hz)

  // Records this tick's boxes (at time t, seconds) and writes into `swept` a copy of
  // `posed` whose every primitive's reach and box grow by its margin: the farthest any
  // corner of its box moved between t - window and t, plus that motion's mean speed times
  // lead. A body whose primitive count changed starts over (margins 0).
  void update(double t, const PosedPrimitives& posed, float window, float lead,
              PosedPrimitives& swept);
  void reset() { count_ = 0; }

 private:
  std::vector<Bounds> boxes_;  // kCapacity x nprim
  std::array<double, kCapacity> times_{};
  int head_ = 0;  // next slot
  int count_ = 0;
  std::size_t prims_ = 0;
};

// One body of the world as the wire names it.
struct WorldBody {
  bool is_prop = false;
  std::uint32_t id = 0;  // member id or prop id
};

// One serialized world part: the bytes after a snapshot's posture entries.
struct WorldPart {
  std::vector<std::uint8_t> bytes;  // prop states (part 0 only), then the section
  std::uint8_t prop_count = 0;
};

class RoomWorld {
 public:
  explicit RoomWorld(const WorldSettings& settings);

  // Members: model may be null (avatar not uploaded yet) or without an implicit model
  // (then the member has a head for spawning but takes no part in collisions).
  void addMember(MemberId id, const SeatPlacement& seat,
                 std::shared_ptr<const CollisionModel> model);
  void setModel(MemberId id, std::shared_ptr<const CollisionModel> model);
  void removeMember(MemberId id);
  // The member's newest accepted posture; its joint count must be the model's (else it is
  // ignored). Decoded at the next step.
  void setPosture(MemberId id, const wire::PostureRecord& record);

  // Props: false when the id exists or the spec is invalid.
  bool addProp(PropId id, const PropSpec& spec, const glm::vec3& position,
               const glm::vec3& velocity);
  void removeProp(PropId id);
  // Where a ball spawned by this member starts: spawn_height_m above its head joint (in its
  // newest posture, else at rest) and a little in front; nullopt for an unknown member or
  // one whose avatar the server does not have yet.
  std::optional<glm::vec3> spawnPointAbove(MemberId id);
  // The member's head joint in room space (newest posture, else at rest); nullopt for an
  // unknown member or one whose avatar the server does not have yet (voice forwarding).
  std::optional<glm::vec3> headPosition(MemberId id);

  // One tick of dt seconds (clamped to (0, 0.1]): pose, step props, Step 1, world parts.
  void step(double dt);

  // Results of the last step.
  std::span<const WorldBody> bodies() const { return bodies_; }
  const InteractionList& interactions() const { return list_; }
  std::span<const WorldPart> parts() const { return {parts_.data(), part_count_}; }
  bool truncated() const { return truncated_; }
  // A prop's current state (null if unknown).
  const BallState* propState(PropId id) const;
  int memberCount() const { return static_cast<int>(members_.size()); }
  int propCount() const { return static_cast<int>(props_.size()); }
  // Balls put back after leaving the world box or reaching an invalid state.
  std::uint64_t propResets() const { return prop_resets_; }

 private:
  struct MemberBody {
    MemberId id;
    glm::mat4 placement{1.0f};  // model -> room
    std::shared_ptr<const CollisionModel> model;
    wire::PostureRecord record;
    bool has_record = false;
    bool dirty = true;  // posture changed since the skeleton was last posed
    Posture posture;
    std::vector<glm::mat4> joint_model;  // (njoint) model space
    std::vector<glm::mat4> skin;         // (njoint) bind -> room
    PosedPrimitives posed[2];
    bool posed_once = false;
    SweptBounds sweep;      // Step 1's motion margins
    PosedPrimitives swept;  // posed[slot_] swollen by them
  };
  struct PropBody {
    PropId id;
    PropSpec spec;
    PrimitiveSet set;  // the sphere, bind pose about the origin
    BallState state;
    glm::vec3 start_position{0.0f};
    glm::vec3 start_velocity{0.0f};
    PosedPrimitives posed[2];
    bool posed_once = false;
    SweptBounds sweep;
    PosedPrimitives swept;
  };

  MemberBody* findMember(MemberId id);
  // Sizes the member's buffers for its model and resets its posture to rest.
  void prepareMember(MemberBody& m);
  // Poses the member's skeleton (joint_model, skin) if its posture changed.
  void poseMemberSkeleton(MemberBody& m);
  void poseProp(PropBody& p, int slot);
  void writeParts();

  WorldSettings settings_;
  std::vector<MemberBody> members_;
  std::vector<PropBody> props_;
  int slot_ = 0;  // which posed[] holds this tick's poses

  // Per tick, reused.
  std::vector<WorldBody> bodies_;
  std::vector<BodyView> views_;
  std::vector<BodyView> previous_views_;
  std::vector<BodyView> swept_views_;  // Step 1's bodies (see SweptBounds)
  double time_ = 0.0;                  // sum of the steps' dt
  InteractionScratch scratch_;
  InteractionList list_;
  std::vector<std::uint32_t> order_;       // pair indices: between bodies, then self-contact
  std::vector<std::uint32_t> part_ends_;   // end of each part in order_
  std::vector<std::uint32_t> body_stamp_;  // part epoch per body (bodies in the part)
  std::vector<std::uint8_t> local_index_;  // body -> index in the part's table
  std::uint32_t epoch_ = 0;
  std::vector<wire::PropStateRecord> prop_records_;
  wire::InteractionSection section_;
  std::vector<WorldPart> parts_;
  std::size_t part_count_ = 0;
  bool truncated_ = false;
  std::uint64_t prop_resets_ = 0;
};

}  // namespace vistel::server
