#include "server/core/voice_forwarding.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vistel::server {
namespace {

constexpr double kLevelTimeConstantS = 0.2;  // loudness smoothing
constexpr double kChallengeLapseS = 0.1;     // a challenge not renewed this long lapses

}  // namespace

VoiceForwarding::VoiceForwarding(const VoiceSettings& settings) : settings_(settings) {
  settings_.max_speakers = std::max(0, settings_.max_speakers);
}

VoiceForwarding::Member* VoiceForwarding::find(std::uint32_t id) {
  for (Member& m : members_) {
    if (m.id == id) return &m;
  }
  return nullptr;
}

const VoiceForwarding::Member* VoiceForwarding::find(std::uint32_t id) const {
  for (const Member& m : members_) {
    if (m.id == id) return &m;
  }
  return nullptr;
}

void VoiceForwarding::addMember(std::uint32_t id, double now) {
  if (find(id) != nullptr) return;
  Member& m = members_.emplace_back();
  m.id = id;
  m.frames = TokenBucket(settings_.max_frames_per_s, settings_.max_frames_burst, now);
  m.bytes = TokenBucket(settings_.max_bytes_per_s, 4.0 * settings_.max_bytes_per_s, now);
  m.slots.reserve(static_cast<std::size_t>(settings_.max_speakers));
}

void VoiceForwarding::removeMember(std::uint32_t id) {
  std::erase_if(members_, [&](const Member& m) { return m.id == id; });
  for (Member& m : members_) {
    std::erase_if(m.slots, [&](const Slot& s) { return s.speaker == id; });
  }
}

void VoiceForwarding::setHead(std::uint32_t id, const glm::vec3& head) {
  if (Member* m = find(id)) m->head = head;
}

bool VoiceForwarding::admit(std::uint32_t speaker, std::size_t bytes, double now) {
  Member* m = find(speaker);
  if (m == nullptr) return false;
  // A refused frame still costs its frame token (a flood stays refused).
  if (!m->frames.take(now, 1.0)) {
    ++stats_.rate_limited;
    return false;
  }
  if (!m->bytes.take(now, static_cast<double>(bytes))) {
    ++stats_.rate_limited;
    return false;
  }
  return true;
}

float VoiceForwarding::score(const Member& s, const Member& l) const {
  const float d = glm::distance(s.head, l.head);
  if (!(d <= settings_.hearing_radius_m)) return -std::numeric_limits<float>::infinity();
  return s.loudness_db - 20.0f * std::log10(std::max(d, 1.0f));
}

void VoiceForwarding::route(std::uint32_t speaker, std::uint8_t level, double now,
                            std::vector<std::uint32_t>& listeners) {
  listeners.clear();
  Member* s = find(speaker);
  if (s == nullptr || !settings_.enabled) return;
  ++stats_.frames;
  // Loudness: the level smoothed over ~200 ms of frames (a new talkspurt starts afresh).
  const float level_db = -static_cast<float>(std::min<std::uint8_t>(level, 127));
  const double gap = now - s->last_frame;
  if (gap > settings_.silence_s) {
    s->loudness_db = level_db;
  } else {
    const auto a = static_cast<float>(1.0 - std::exp(-std::max(gap, 0.0) / kLevelTimeConstantS));
    s->loudness_db += a * (level_db - s->loudness_db);
  }
  s->last_frame = now;
  const auto capacity = static_cast<std::size_t>(settings_.max_speakers);

  for (Member& l : members_) {
    if (l.id == speaker) continue;
    const float mine = score(*s, l);
    auto slot = std::find_if(l.slots.begin(), l.slots.end(),
                             [&](const Slot& x) { return x.speaker == speaker; });
    if (std::isinf(mine)) {
      if (slot != l.slots.end()) l.slots.erase(slot);
      ++stats_.out_of_range;
      continue;
    }
    if (slot != l.slots.end()) {
      listeners.push_back(l.id);
      ++stats_.forwarded;
      continue;
    }
    // Not in the set: free the places of speakers gone silent or out of range.
    std::erase_if(l.slots, [&](const Slot& x) {
      const Member* other = find(x.speaker);
      return other == nullptr || now - other->last_frame > settings_.silence_s ||
             std::isinf(score(*other, l));
    });
    if (l.slots.size() < capacity) {
      l.slots.push_back({speaker, -1.0, -1.0});
      listeners.push_back(l.id);
      ++stats_.forwarded;
      continue;
    }
    if (capacity == 0) {
      ++stats_.not_selected;
      continue;
    }
    // A full set: challenge its weakest speaker.
    Slot* weakest = nullptr;
    float weakest_score = std::numeric_limits<float>::infinity();
    for (Slot& x : l.slots) {
      const float v = score(*find(x.speaker), l);
      if (v < weakest_score) {
        weakest_score = v;
        weakest = &x;
      }
    }
    if (mine > weakest_score) {
      if (weakest->outranked_since < 0.0 || now - weakest->outranked_last > kChallengeLapseS) {
        weakest->outranked_since = now;
      }
      weakest->outranked_last = now;
      if (now - weakest->outranked_since >= settings_.hold_s) {
        *weakest = {speaker, -1.0, -1.0};
        ++stats_.replacements;
        listeners.push_back(l.id);
        ++stats_.forwarded;
        continue;
      }
    }
    ++stats_.not_selected;
  }
}

std::vector<std::uint32_t> VoiceForwarding::speakersOf(std::uint32_t listener) const {
  std::vector<std::uint32_t> out;
  if (const Member* l = find(listener)) {
    for (const Slot& x : l->slots) out.push_back(x.speaker);
  }
  return out;
}

}  // namespace vistel::server
