#include "server/shell/datagram_drops.hpp"

#include <fmt/format.h>

namespace vistel::server {

std::string_view dropClassName(DropClass c) {
  switch (c) {
    case DropClass::kBadHeader:
      return "bad header";
    case DropClass::kUnknownKey:
      return "unknown key";
    case DropClass::kUnverifiedAddress:
      return "unverified address";
    case DropClass::kRate:
      return "rate";
    case DropClass::kBadPayload:
      return "bad payload";
    case DropClass::kReplay:
      return "replay";
    case DropClass::kOther:
      break;
  }
  return "other";
}

DropClass classifyDropReason(std::string_view reason) {
  // The phrases routeDatagram and Room use (server/core); new ones fall under "other"
  // until they are named here.
  struct Entry {
    std::string_view phrase;
    DropClass cls;
  };
  static constexpr Entry kTable[] = {
      {"not a vistel datagram", DropClass::kBadHeader},
      {"truncated datagram", DropClass::kBadHeader},
      {"server-bound datagram of a client-bound type", DropClass::kBadHeader},
      {"malformed hello", DropClass::kBadHeader},
      {"datagram for unknown member", DropClass::kUnknownKey},
      {"hello for unknown member", DropClass::kUnknownKey},
      {"hello with bad key", DropClass::kUnknownKey},
      {"endpoint already bound", DropClass::kUnverifiedAddress},
      {"unknown member", DropClass::kUnknownKey},
      {"bad key", DropClass::kUnknownKey},
      {"endpoint not bound", DropClass::kUnverifiedAddress},
      {"wrong endpoint", DropClass::kUnverifiedAddress},
      {"unexpected datagram", DropClass::kBadPayload},
      {"malformed posture", DropClass::kBadPayload},
      {"malformed ping", DropClass::kBadPayload},
      {"avatar not ready", DropClass::kBadPayload},
      {"wrong joint count", DropClass::kBadPayload},
      {"capture time in the future", DropClass::kBadPayload},
      // Sealed datagrams (proto/WIRE.md §3.9).
      {"oversized datagram", DropClass::kBadHeader},
      {"bad datagram tag", DropClass::kUnknownKey},
      {"hello with bad tag", DropClass::kUnknownKey},
      {"replayed datagram", DropClass::kReplay},
      {"datagram too old", DropClass::kReplay},
      {"invalid counter", DropClass::kReplay},
      {"capture time too old", DropClass::kBadPayload},
      {"sequence jump", DropClass::kBadPayload},
      // Voice (proto/WIRE.md §3.10); "voice rate limit" is a rate drop by its name.
      {"malformed voice", DropClass::kBadPayload},
      {"voice disabled", DropClass::kBadPayload},
  };
  for (const Entry& e : kTable) {
    if (e.phrase == reason) return e.cls;
  }
  if (reason.find("rate") != std::string_view::npos) return DropClass::kRate;
  return DropClass::kOther;
}

std::optional<std::string> DatagramDrops::add(std::string_view reason, double now) {
  const auto cls = static_cast<std::size_t>(classifyDropReason(reason));
  counts_[cls].fetch_add(1, std::memory_order_relaxed);

  // Summarise at most once per interval: what was dropped since the last summary.
  std::lock_guard lock(mutex_);
  ++since_[cls];
  if (now - logged_at_ < interval_s_) return std::nullopt;
  const double span = logged_at_ < -1e299 ? 0.0 : now - logged_at_;
  std::string parts;
  std::uint64_t n = 0;
  for (int c = 0; c < kDropClassCount; ++c) {
    const std::uint64_t k = since_[static_cast<std::size_t>(c)];
    if (k == 0) continue;
    n += k;
    parts += fmt::format("{}{} {}", parts.empty() ? "" : ", ", k,
                         dropClassName(static_cast<DropClass>(c)));
  }
  since_ = {};
  logged_at_ = now;
  if (span == 0.0) return fmt::format("dropped {} datagram(s): {} (last: {})", n, parts, reason);
  return fmt::format("dropped {} datagram(s) in the last {:.0f} s: {} (last: {})", n, span, parts,
                     reason);
}

std::uint64_t DatagramDrops::total() const {
  std::uint64_t n = 0;
  for (const auto& c : counts_) n += c.load(std::memory_order_relaxed);
  return n;
}

std::map<std::string, std::uint64_t> DatagramDrops::byReason() const {
  std::map<std::string, std::uint64_t> out;
  for (int c = 0; c < kDropClassCount; ++c) {
    out[std::string(dropClassName(static_cast<DropClass>(c)))] = count(static_cast<DropClass>(c));
  }
  return out;
}

}  // namespace vistel::server
