#include "client/net/net_sim.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <set>

#include <fmt/format.h>

#include "client/net/net_driver.hpp"

namespace vistel::net {
namespace {

constexpr double kMaxDuration = 10.0;  // seconds, any one duration key

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// A plain decimal number (from_chars: no sign other than '-', no spaces); false otherwise.
bool parseNumber(std::string_view text, double& out) {
  if (text.empty()) return false;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && end == text.data() + text.size() && std::isfinite(out);
}

// "0.1" or "10%": a probability in [0, 1].
bool parseProbability(std::string_view text, double& out) {
  double scale = 1.0;
  if (!text.empty() && text.back() == '%') {
    text.remove_suffix(1);
    scale = 0.01;
  }
  if (!parseNumber(text, out)) return false;
  out *= scale;
  return out >= 0.0 && out <= 1.0;
}

// "30ms", "0.03s", "500us": seconds in [0, kMaxDuration].
bool parseDuration(std::string_view text, double& out) {
  double scale = 0.0;
  if (text.size() > 2 && text.substr(text.size() - 2) == "ms") {
    scale = 1e-3;
    text.remove_suffix(2);
  } else if (text.size() > 2 && text.substr(text.size() - 2) == "us") {
    scale = 1e-6;
    text.remove_suffix(2);
  } else if (text.size() > 1 && text.back() == 's') {
    scale = 1.0;
    text.remove_suffix(1);
  } else {
    return false;
  }
  if (!parseNumber(text, out)) return false;
  out *= scale;
  return out >= 0.0 && out <= kMaxDuration;
}

std::string formatDuration(double s) { return fmt::format("{:g}ms", s * 1e3); }

}  // namespace

bool NetSimSpec::active() const {
  return loss > 0.0 || latency_s > 0.0 || jitter_s > 0.0 || dup > 0.0 || reorder > 0.0;
}

Result<NetSimSpec> parseNetSimSpec(std::string_view text, std::string_view what) {
  NetSimSpec spec;
  const std::string_view whole = trim(text);
  if (whole.empty() || whole == "off") return spec;
  std::set<std::string, std::less<>> seen;
  std::string_view rest = whole;
  while (true) {
    const std::size_t comma = rest.find(',');
    const std::string_view item = trim(rest.substr(0, comma));
    const std::size_t eq = item.find('=');
    if (item.empty()) {
      return fail("{} '{}': an empty item (two commas, or one at an end)", what, whole);
    }
    if (eq == std::string_view::npos) {
      return fail("{} '{}': '{}' is not KEY=VALUE", what, whole, item);
    }
    const std::string_view key = trim(item.substr(0, eq));
    const std::string_view value = trim(item.substr(eq + 1));
    if (!seen.insert(std::string(key)).second) {
      return fail("{} '{}': '{}' is given twice", what, whole, key);
    }
    const auto bad = [&](std::string_view expected) {
      return fail("{} '{}': {}='{}': expected {}", what, whole, key, value, expected);
    };
    const char* kProbability = "a probability in [0, 1] (0.1 or 10%)";
    const char* kDuration = "a duration in [0, 10 s] with a unit (us, ms, s), e.g. 30ms";
    if (key == "loss") {
      if (!parseProbability(value, spec.loss)) return bad(kProbability);
    } else if (key == "dup") {
      if (!parseProbability(value, spec.dup)) return bad(kProbability);
    } else if (key == "reorder") {
      if (!parseProbability(value, spec.reorder)) return bad(kProbability);
    } else if (key == "latency") {
      if (!parseDuration(value, spec.latency_s)) return bad(kDuration);
    } else if (key == "jitter") {
      if (!parseDuration(value, spec.jitter_s)) return bad(kDuration);
    } else if (key == "reorder_delay") {
      if (!parseDuration(value, spec.reorder_delay_s)) return bad(kDuration);
    } else if (key == "jitter_dist") {
      if (value == "uniform") {
        spec.jitter_dist = JitterDistribution::kUniform;
      } else if (value == "normal") {
        spec.jitter_dist = JitterDistribution::kNormal;
      } else {
        return bad("uniform or normal");
      }
    } else if (key == "dir") {
      if (value == "both") {
        spec.direction = NetSimDirection::kBoth;
      } else if (value == "in") {
        spec.direction = NetSimDirection::kIn;
      } else if (value == "out") {
        spec.direction = NetSimDirection::kOut;
      } else {
        return bad("both, in or out");
      }
    } else if (key == "seed") {
      std::uint64_t seed = 0;
      const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), seed);
      if (value.empty() || ec != std::errc() || end != value.data() + value.size()) {
        return bad("a decimal number below 2^64");
      }
      spec.seed = seed;
    } else {
      return fail(
          "{} '{}': unknown key '{}' (known: loss, latency, jitter, jitter_dist, dup, reorder, "
          "reorder_delay, dir, seed)",
          what, whole, key);
    }
    if (comma == std::string_view::npos) break;
    rest = rest.substr(comma + 1);
  }
  return spec;
}

std::string describeNetSim(const NetSimSpec& spec) {
  if (!spec.active()) return "off";
  const char* dist = spec.jitter_dist == JitterDistribution::kNormal ? "normal" : "uniform";
  const char* dir = spec.direction == NetSimDirection::kIn    ? "in"
                    : spec.direction == NetSimDirection::kOut ? "out"
                                                              : "both";
  return fmt::format(
      "loss={:g},latency={},jitter={},jitter_dist={},dup={:g},reorder={:g},reorder_delay={},"
      "dir={}{}",
      spec.loss, formatDuration(spec.latency_s), formatDuration(spec.jitter_s), dist, spec.dup,
      spec.reorder, formatDuration(spec.reorder_delay_s), dir,
      spec.seed != 0 ? fmt::format(",seed={}", spec.seed) : std::string());
}

std::uint64_t netSimSeed(const NetSimSpec& spec, const std::string& name) {
  if (spec.seed == 0)
    return (static_cast<std::uint64_t>(std::random_device{}()) << 32) ^ std::random_device{}();
  // FNV-1a of the name, mixed with the seed (splitmix64's finaliser).
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (const char c : name) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ull;
  std::uint64_t z = spec.seed ^ h;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// --- NetSimLink -------------------------------------------------------------------------

namespace {

// Heap order: the earliest due (then the first pushed) on top.
struct Later {
  template <typename P>
  bool operator()(const P& a, const P& b) const {
    return a.due != b.due ? a.due > b.due : a.order > b.order;
  }
};

}  // namespace

NetSimLink::NetSimLink(const NetSimSpec& spec, std::uint64_t seed) : spec_(spec), rng_(seed) {}

double NetSimLink::delay() {
  double d = spec_.latency_s;
  if (spec_.jitter_s > 0.0) {
    if (spec_.jitter_dist == JitterDistribution::kNormal) {
      d += std::abs(std::normal_distribution<double>(0.0, spec_.jitter_s)(rng_));
    } else {
      d += std::uniform_real_distribution<double>(0.0, spec_.jitter_s)(rng_);
    }
  }
  return d;
}

void NetSimLink::enqueue(std::span<const std::uint8_t> bytes, double due) {
  if (queue_.size() >= kMaxQueued) {
    ++counters_.overflowed;
    return;
  }
  Pending p;
  p.due = due;
  p.order = next_order_++;
  if (!spare_.empty()) {
    p.bytes = std::move(spare_.back());
    spare_.pop_back();
  }
  p.bytes.assign(bytes.begin(), bytes.end());
  queue_.push_back(std::move(p));
  std::push_heap(queue_.begin(), queue_.end(), Later{});
}

void NetSimLink::push(std::span<const std::uint8_t> bytes, double now) {
  ++counters_.offered;
  // Each decision draws from the generator every time, so that one fault's probability
  // does not shift the others' random streams.
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const bool lost = unit(rng_) < spec_.loss;
  const bool duplicate = unit(rng_) < spec_.dup;
  const bool held_back = unit(rng_) < spec_.reorder;
  const double first_delay = delay();
  const double second_delay = delay();
  if (lost) {
    ++counters_.lost;
    return;
  }
  double due = now + first_delay;
  if (held_back) {
    ++counters_.reordered;
    due += spec_.reorder_delay_s;
  }
  enqueue(bytes, due);
  if (duplicate) {
    ++counters_.duplicated;
    enqueue(bytes, now + second_delay);
  }
}

bool NetSimLink::nextDue(double& due) const {
  if (queue_.empty()) return false;
  due = queue_.front().due;
  return true;
}

bool NetSimLink::pop(double now, std::vector<std::uint8_t>& out) {
  if (queue_.empty() || queue_.front().due > now) return false;
  std::pop_heap(queue_.begin(), queue_.end(), Later{});
  out.swap(queue_.back().bytes);
  spare_.push_back(std::move(queue_.back().bytes));  // out's old buffer, for reuse
  if (spare_.size() > 64) spare_.pop_back();
  queue_.pop_back();
  ++counters_.delivered;
  return true;
}

void NetSimLink::clear() {
  for (Pending& p : queue_) {
    if (spare_.size() < 64) spare_.push_back(std::move(p.bytes));
  }
  queue_.clear();
}

// --- NetSim -------------------------------------------------------------------------------

NetSim::NetSim(asio::any_io_executor executor, const NetSimSpec& spec, std::uint64_t seed,
               Deliver to_server, Deliver to_program)
    : spec_(spec),
      out_(spec, seed),
      in_(spec, seed ^ 0x9e3779b97f4a7c15ull),
      to_server_(std::move(to_server)),
      to_program_(std::move(to_program)),
      timer_(std::move(executor)) {}

void NetSim::send(std::span<const std::uint8_t> datagram, double now) {
  if (!spec_.appliesOut()) {
    to_server_(datagram);
    return;
  }
  out_.push(datagram, now);
  arm();
}

void NetSim::receive(std::span<const std::uint8_t> datagram, double now) {
  if (!spec_.appliesIn()) {
    to_program_(datagram);
    return;
  }
  in_.push(datagram, now);
  arm();
}

void NetSim::clear() {
  out_.clear();
  in_.clear();
  armed_for_ = -1.0;
  timer_.cancel();
}

void NetSim::arm() {
  // The earliest due time of either direction; re-arm only when it moved earlier.
  double due = 0.0;
  double in_due = 0.0;
  const bool has_out = out_.nextDue(due);
  if (in_.nextDue(in_due) && (!has_out || in_due < due)) due = in_due;
  if (!has_out && in_.inFlight() == 0) return;
  if (armed_for_ >= 0.0 && armed_for_ <= due) return;
  armed_for_ = due;
  const double wait = std::max(0.0, due - monotonicSeconds());
  timer_.expires_after(std::chrono::duration_cast<asio::steady_timer::duration>(
      std::chrono::duration<double>(wait)));
  timer_.async_wait([weak = weak_from_this(), due](const boost::system::error_code& ec) {
    auto self = weak.lock();
    if (ec || !self || self->armed_for_ != due) return;  // cancelled or superseded
    self->armed_for_ = -1.0;
    self->deliverDue();
    self->arm();
  });
}

void NetSim::deliverDue() {
  // Everything due by now, each direction in due order.
  const double now = monotonicSeconds();
  while (out_.pop(now, scratch_)) to_server_(scratch_);
  while (in_.pop(now, scratch_)) to_program_(scratch_);
}

}  // namespace vistel::net
