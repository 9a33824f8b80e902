#include "client/net/playback_stats.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace vistel::net {
namespace {

constexpr double kGrowth = 1.02;  // each bin 2% wider than the one before
const double kLogGrowth = std::log(kGrowth);

// Bin 0: below 1 ms; bin i >= 1: [kGrowth^(i-1), kGrowth^i) ms; the last takes the rest.
std::size_t binOf(double ms) {
  if (!(ms >= 1.0)) return 0;
  const double i = 1.0 + std::floor(std::log(ms) / kLogGrowth);
  return static_cast<std::size_t>(std::min(i, static_cast<double>(AgeHistogram::kBins - 1)));
}

// A representative value of bin i: its geometric middle (0.5 ms for bin 0).
double binValue(std::size_t i) {
  if (i == 0) return 0.5;
  return std::pow(kGrowth, static_cast<double>(i) - 0.5);
}

nlohmann::json figuresJson(const ShownFigures& f) {
  nlohmann::json doc = {{"frames", f.frames()},
                        {"interpolated", f.interpolated},
                        {"held", f.held},
                        {"extrapolated", f.extrapolated},
                        {"age_ms",
                         {{"p50", f.age_ms.percentile(50.0)},
                          {"p99", f.age_ms.percentile(99.0)},
                          {"mean", f.age_ms.mean()},
                          {"max", f.age_ms.max()}}}};
  if (f.drawn_jerk.count() > 0 && f.sent_jerk.count() > 0) {
    const double sent = f.sent_jerk.mean();
    doc["jerk"] = {{"drawn", f.drawn_jerk.mean()},
                   {"sent", sent},
                   {"ratio", sent > 0.0 ? f.drawn_jerk.mean() / sent : 0.0}};
  }
  return doc;
}

}  // namespace

void AgeHistogram::add(double ms) {
  if (!std::isfinite(ms)) return;
  ms = std::max(ms, 0.0);  // a clock estimate a little off can make a fresh posture "future"
  ++bins_[binOf(ms)];
  ++count_;
  sum_ += ms;
  max_ = std::max(max_, ms);
}

double AgeHistogram::percentile(double p) const {
  if (count_ == 0) return 0.0;
  const auto rank = std::max<std::uint64_t>(
      1, static_cast<std::uint64_t>(
             std::ceil(std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(count_))));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < kBins; ++i) {
    seen += bins_[i];
    if (seen >= rank) return std::min(binValue(i), max_);
  }
  return max_;
}

void AgeHistogram::merge(const AgeHistogram& other) {
  for (std::size_t i = 0; i < kBins; ++i) bins_[i] += other.bins_[i];
  count_ += other.count_;
  sum_ += other.sum_;
  max_ = std::max(max_, other.max_);
}

void ShownFigures::add(JitterBuffer::Shown kind, double age_s) {
  switch (kind) {
    case JitterBuffer::Shown::kNone:
      return;
    case JitterBuffer::Shown::kInterpolated:
      ++interpolated;
      break;
    case JitterBuffer::Shown::kHeld:
      ++held;
      break;
    case JitterBuffer::Shown::kExtrapolated:
      ++extrapolated;
      break;
  }
  age_ms.add(age_s * 1e3);
}

void ShownFigures::merge(const ShownFigures& other) {
  interpolated += other.interpolated;
  held += other.held;
  extrapolated += other.extrapolated;
  age_ms.merge(other.age_ms);
  drawn_jerk.merge(other.drawn_jerk);
  sent_jerk.merge(other.sent_jerk);
}

void PlaybackStats::add(const std::string& member, JitterBuffer::Shown kind, double age_s) {
  if (kind == JitterBuffer::Shown::kNone) return;
  total_.add(kind, age_s);
  this->member(member).add(kind, age_s);
}

ShownFigures& PlaybackStats::member(const std::string& name) {
  auto it = members_.find(name);
  if (it == members_.end()) it = members_.emplace(name, ShownFigures{}).first;
  return it->second;
}

void PlaybackStats::addDrawn(const std::string& name, double t, std::span<const glm::vec3> joints) {
  const double jerk = member(name).drawn_jerk.add(t, joints);
  if (jerk >= 0.0) total_.drawn_jerk.addValue(jerk);
}

void PlaybackStats::addSent(const std::string& name, double t, std::span<const glm::vec3> joints) {
  const double jerk = member(name).sent_jerk.add(t, joints);
  if (jerk >= 0.0) total_.sent_jerk.addValue(jerk);
}

void PlaybackStats::merge(const PlaybackStats& other) {
  total_.merge(other.total_);
  for (const auto& [name, f] : other.members_) members_[name].merge(f);
}

std::string playbackJson(const PlaybackStats& stats) {
  nlohmann::json doc = figuresJson(stats.total());
  if (!stats.members().empty()) {
    doc["members"] = nlohmann::json::object();
    for (const auto& [name, f] : stats.members()) doc["members"][name] = figuresJson(f);
  }
  return doc.dump();
}

std::string playbackSummary(const ShownFigures& f) {
  const double frames = static_cast<double>(std::max<std::uint64_t>(f.frames(), 1));
  return fmt::format(
      "{} frames: {:.1f}% interpolated, {} held, {} extrapolated; age p50 {:.1f} ms, p99 {:.1f} "
      "ms",
      f.frames(), 100.0 * static_cast<double>(f.interpolated) / frames, f.held, f.extrapolated,
      f.age_ms.percentile(50.0), f.age_ms.percentile(99.0));
}

}  // namespace vistel::net
