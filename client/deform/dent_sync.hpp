// Shared dents, the site client's side (proto/SESSION.md §2.5): which bodies' elastic memory
// this site sends, when, and which records from other sites it takes, so that a dent made
// at one site is drawn at every site and survives scene rebuilds and late joins.
//
// A site speaks for its own avatar always, and for a prop while its own avatar touches it
// and for linger_s after (the dent's final shape; a viscoelastic one's recovery then runs
// alike everywhere). For each body it speaks for, collect() reads its memory once per
// min_interval_s and gives the record when it differs from the last one sent for it (so at
// most once per interval: the server ignores faster ones, [limits] dents_interval_s). A body
// that never had a dent sends nothing.
//
// receive() replaces a body's memory with another site's record (RoomDeformer::adoptDents),
// except for a body this site speaks for at that moment: there its own contact is newer.
// A prop dented at two sites at once ends with the dents of whichever site let go last.
//
// Not thread-safe: the client's frame thread calls it between RoomDeformer::finish() and
// the next sync(). Allocates only when a body is first seen or a record grows.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "client/deform/room_deformer.hpp"
#include "common/base/result.hpp"
#include "common/scene/dent_record.hpp"

namespace vistel {

struct DentSyncSettings {
  double min_interval_s = 0.25;  // between two records of one body (>= the server's 0.2 s)
  double linger_s = 1.0;         // a prop stays ours this long after our avatar let go
};

// A body as the session names it (member id or prop id) and as the view draws it.
struct DentBody {
  bool prop = false;
  std::uint32_t id = 0;       // member id (its avatar) or prop id
  std::uint32_t view_id = 0;  // MemberView::id (a member's id; propViewId for a prop)
};

struct OutgoingDents {
  DentBody body;
  DentRecord record;
};

struct DentSyncCounters {
  std::uint64_t sent = 0;     // records collect() gave
  std::uint64_t adopted = 0;  // records received and written into a body (or waiting for it)
  std::uint64_t skipped = 0;  // records received for a body this site speaks for
  std::uint64_t failed = 0;   // records received that the body refused (another mesh)
};

class DentSync {
 public:
  explicit DentSync(const DentSyncSettings& settings = {}) : settings_(settings) {}

  // After RoomDeformer::finish(): the records to send this frame for `self` (our avatar) and
  // the drawn props. now: seconds, any monotonic clock. Valid until the next call.
  std::span<const OutgoingDents> collect(const RoomDeformer& deformer, double now,
                                         const DentBody& self, std::span<const DentBody> props);
  // Another site's record for `body` (relayed by the server), sampled age_s ago (by the
  // server clock; a viscoelastic dent recovers over it), given our avatar `self`. Skipped
  // (ok) for a body we speak for; else adopted. The error names the body.
  Status receive(RoomDeformer& deformer, double now, const DentBody& self, const DentBody& body,
                 const DentRecord& record, double age_s = 0.0);

  const DentSyncCounters& counters() const { return counters_; }
  // "dent_sync": {"sent": n, "adopted": n, "skipped": n, "failed": n} (a JSON member).
  std::string json() const;

 private:
  struct Tracked {
    bool prop = false;
    std::uint32_t id = 0;
    DentRecord last;             // last record sent or adopted
    bool have_last = false;      // ... there was one
    double checked_at = -1e300;  // when offer() last read its memory
    double touched_at = -1e300;  // a prop: when our avatar last touched it
  };
  Tracked& tracked(const DentBody& body);
  // Whether this site speaks for the body at `now`.
  bool ours(const Tracked& t, const DentBody& self, double now) const;
  // Gives the body's record when it changed and the interval allows.
  void offer(const RoomDeformer& deformer, double now, const DentBody& body, Tracked& t);

  DentSyncSettings settings_;
  std::vector<Tracked> tracked_;
  std::vector<OutgoingDents> out_;
  std::size_t out_count_ = 0;
  DentRecord scratch_;
  DentSyncCounters counters_;
};

}  // namespace vistel
