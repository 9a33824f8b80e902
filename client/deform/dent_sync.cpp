#include "client/deform/dent_sync.hpp"

#include <algorithm>

#include <fmt/format.h>

namespace vistel {

DentSync::Tracked& DentSync::tracked(const DentBody& body) {
  auto it = std::find_if(tracked_.begin(), tracked_.end(),
                         [&](const Tracked& t) { return t.prop == body.prop && t.id == body.id; });
  if (it != tracked_.end()) return *it;
  Tracked& t = tracked_.emplace_back();
  t.prop = body.prop;
  t.id = body.id;
  return t;
}

bool DentSync::ours(const Tracked& t, const DentBody& self, double now) const {
  if (!t.prop) return t.id == self.id;
  return now - t.touched_at <= settings_.linger_s;
}

void DentSync::offer(const RoomDeformer& deformer, double now, const DentBody& body, Tracked& t) {
  // The body's memory is read (O(vertices)) at most once per interval, so records also go
  // at most once per interval.
  if (now - t.checked_at < settings_.min_interval_s) return;
  t.checked_at = now;
  if (!deformer.recordDents(body.view_id, scratch_)) return;  // not a deforming body
  if (t.have_last ? scratch_ == t.last : scratch_.depths.empty()) return;
  if (out_count_ == out_.size()) out_.emplace_back();
  OutgoingDents& o = out_[out_count_++];
  o.body = body;
  o.record = scratch_;
  t.last = scratch_;
  t.have_last = true;
  ++counters_.sent;
}

std::span<const OutgoingDents> DentSync::collect(const RoomDeformer& deformer, double now,
                                                 const DentBody& self,
                                                 std::span<const DentBody> props) {
  out_count_ = 0;
  // Props no longer drawn are forgotten, and avatars but ours (another member's, or ours
  // under an id a reconnection replaced): nothing is sent for them.
  std::erase_if(tracked_, [&](const Tracked& t) {
    if (!t.prop) return t.id != self.id;
    return std::none_of(props.begin(), props.end(),
                        [&](const DentBody& p) { return p.id == t.id; });
  });
  if (self.id != 0) offer(deformer, now, self, tracked(self));
  for (const DentBody& p : props) {
    Tracked& t = tracked(p);
    if (self.id != 0 && deformer.touching(self.view_id, p.view_id)) t.touched_at = now;
    if (ours(t, self, now)) offer(deformer, now, p, t);
  }
  return std::span<const OutgoingDents>(out_.data(), out_count_);
}

Status DentSync::receive(RoomDeformer& deformer, double now, const DentBody& self,
                         const DentBody& body, const DentRecord& record, double age_s) {
  Tracked& t = tracked(body);
  if (ours(t, self, now)) {
    ++counters_.skipped;
    return {};
  }
  if (Status st = deformer.adoptDents(body.view_id, record, age_s); !st) {
    ++counters_.failed;
    return fail("dents of {} {:#x}: {}", body.prop ? "prop" : "member", body.id,
                st.error().message);
  }
  t.last = record;  // what we would send, should we touch it next
  t.have_last = true;
  ++counters_.adopted;
  return {};
}

std::string DentSync::json() const {
  return fmt::format(R"(  "dent_sync": {{"sent": {}, "adopted": {}, "skipped": {}, "failed": {}}})",
                     counters_.sent, counters_.adopted, counters_.skipped, counters_.failed);
}

}  // namespace vistel
