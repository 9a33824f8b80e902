// The server's Step 1 list (DESIGN.md §6: the server owns the collision world) mapped onto
// the client's deformable scene. The session names bodies by member and prop ids in the
// roster's order; the RoomDeformer has only the drawn bodies with implicit models, in view
// order. Members map by id, props by their view id (propViewId).
#pragma once

#include <cstdint>
#include <vector>

#include "client/deform/room_deformer.hpp"
#include "client/net/client_session.hpp"
#include "common/base/result.hpp"
#include "common/deform/interactions.hpp"

namespace vistel {

class ServerInteractions {
 public:
  // Fills `out` (the deformer's body indices) from the session's newest complete list.
  // False when there is none yet, or it does not fit the bodies (logged once per list):
  // the caller then lets the scene compute Step 1 itself. Allocation-free once warm.
  bool map(const net::ClientSession& session, const RoomDeformer& deformer, InteractionList& out);

  // Lists used, and lists that did not fit.
  std::uint64_t used() const { return used_; }
  std::uint64_t refused() const { return refused_; }

 private:
  std::vector<BodyView> bodies_;  // session order
  std::vector<int> to_body_;      // session order -> deformer body
  InteractionList session_list_;
  std::uint64_t last_refused_version_ = 0;
  std::uint64_t used_ = 0;
  std::uint64_t refused_ = 0;
};

}  // namespace vistel
