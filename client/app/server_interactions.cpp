#include "client/app/server_interactions.hpp"

#include <spdlog/spdlog.h>

#include "client/net/prop_models.hpp"

namespace vistel {

bool ServerInteractions::map(const net::ClientSession& session, const RoomDeformer& deformer,
                             InteractionList& out) {
  const std::uint64_t version = session.interactionsVersion();
  const std::span<const BodyView> views = deformer.bodyViews();
  if (version == 0 || views.empty()) return false;
  bodies_.clear();
  to_body_.clear();
  const auto add = [&](std::uint32_t view_id) {
    const int body = deformer.bodyOf(view_id);
    to_body_.push_back(body);
    bodies_.push_back(body >= 0 ? views[static_cast<std::size_t>(body)] : BodyView{});
  };
  for (const auto& m : session.members()) add(m->id);
  for (const auto& p : session.props()) add(net::propViewId(p->id));
  // Each body's own pairs are left to the deformer, which adds them for the bodies it
  // deforms this frame (RoomDeformer::prepare).
  if (Status st = session.sceneInteractions(bodies_, session_list_, nullptr, false); !st) {
    ++refused_;
    if (version != last_refused_version_) {
      last_refused_version_ = version;
      spdlog::warn("server interactions not used this frame: {}", st.error().message);
    }
    return false;
  }
  out.pairs.clear();
  for (const Interaction& p : session_list_.pairs) {
    const int a = to_body_[p.body_a];
    const int b = to_body_[p.body_b];
    if (a < 0 || b < 0) continue;  // left out by sceneInteractions already
    out.pairs.push_back(
        {static_cast<std::uint16_t>(a), p.prim_a, static_cast<std::uint16_t>(b), p.prim_b});
  }
  finalizeInteractions(out, deformer.bodyCount());
  ++used_;
  return true;
}

}  // namespace vistel
