// The collision world of one room (DESIGN.md §1, §6): every member's collision model
// (skeleton, primitives, combination graph) posed from its newest posture at its seat,
// the room's props, and per tick
//   1. pose every member's primitives (placement x skinning matrices),
//   2. step every ball by the fields' reaction of everything else (stepBall: gravity,
//      floor, restitution; the surfaces' velocities from the previous tick's poses),
//   3. Step 1 across bodies, and within them when send_self_contact (buildInteractions),
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
