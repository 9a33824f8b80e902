#include "client/net/jitter_buffer.hpp"

#include <algorithm>
#include <cassert>

namespace vistel::net {
namespace {

// Cubic Hermite interpolation at t between postures a and b (times ascending), with the
// tangents of a non-uniform Catmull-Rom spline from their neighbours p (before a) and n
// (after b) where present, else the chord's (so the motion's velocity is continuous across
// every key, and at the newest key it matches the linear extrapolation beyond). Rotations:
// the same on the quaternions' components (signs aligned along the chain), normalised.
// out.rotations is resized to a's joint count; every posture given has that count.
void hermitePostures(const Posture* p, const Posture& a, const Posture& b, const Posture* n,
                     double t, Posture& out) {
  const double span = b.time - a.time;
  const double s = span > 0.0 ? std::clamp((t - a.time) / span, 0.0, 1.0) : 1.0;
  const double s2 = s * s, s3 = s2 * s;
  const auto h00 = static_cast<float>(2.0 * s3 - 3.0 * s2 + 1.0);
  const auto h10 = static_cast<float>((s3 - 2.0 * s2 + s) * span);
  const auto h01 = static_cast<float>(-2.0 * s3 + 3.0 * s2);
  const auto h11 = static_cast<float>((s3 - s2) * span);
  const float chord = span > 0.0 ? static_cast<float>(1.0 / span) : 0.0f;
  // A neighbour at the same capture time as the far key (a sender's clock that stood still)
  // gives no tangent: the chord's instead.
  const bool use_p = p != nullptr && b.time - p->time > 0.0;
  const bool use_n = n != nullptr && n->time - a.time > 0.0;
  const float before = use_p ? static_cast<float>(1.0 / (b.time - p->time)) : 0.0f;
  const float after = use_n ? static_cast<float>(1.0 / (n->time - a.time)) : 0.0f;
  const auto cubic = [&](const glm::vec4& vp, const glm::vec4& va, const glm::vec4& vb,
                         const glm::vec4& vn) {
    const glm::vec4 ma = use_p ? (vb - vp) * before : (vb - va) * chord;
    const glm::vec4 mb = use_n ? (vn - va) * after : (vb - va) * chord;
    return h00 * va + h10 * ma + h01 * vb + h11 * mb;
  };
  const glm::vec3 rp = p != nullptr ? p->root_translation : a.root_translation;
  const glm::vec3 rn = n != nullptr ? n->root_translation : b.root_translation;
  out.root_translation = glm::vec3(cubic(glm::vec4(rp, 0.0f), glm::vec4(a.root_translation, 0.0f),
                                         glm::vec4(b.root_translation, 0.0f), glm::vec4(rn, 0.0f)));
  const std::size_t nj = a.rotations.size();
  out.rotations.resize(nj);
  const auto vec = [](const glm::quat& q) { return glm::vec4(q.x, q.y, q.z, q.w); };
  for (std::size_t j = 0; j < nj; ++j) {
    const glm::vec4 qa = vec(a.rotations[j]);
    glm::vec4 qb = vec(b.rotations[j]);
    if (glm::dot(qa, qb) < 0.0f) qb = -qb;
    glm::vec4 qp = p != nullptr ? vec(p->rotations[j]) : qa;
    if (glm::dot(qp, qa) < 0.0f) qp = -qp;
    glm::vec4 qn = n != nullptr ? vec(n->rotations[j]) : qb;
    if (glm::dot(qn, qb) < 0.0f) qn = -qn;
    const glm::vec4 q = cubic(qp, qa, qb, qn);
    const float len = glm::length(q);
    out.rotations[j] =
        len > 0.0f ? glm::quat(q.w / len, q.x / len, q.y / len, q.z / len) : a.rotations[j];
  }
  out.time = t;
}

}  // namespace

JitterBuffer::JitterBuffer(int capacity) : entries_(static_cast<std::size_t>(capacity)) {
  assert(capacity >= 2);
}

JitterBuffer::Push JitterBuffer::push(std::uint16_t sequence, const Posture& posture) {
  // Refuse what is already here, and what is older than everything when full.
  for (int i = 0; i < count_; ++i) {
    if (entries_[static_cast<std::size_t>(i)].sequence == sequence) return Push::kDuplicate;
  }
  const int capacity = static_cast<int>(entries_.size());
  if (count_ == capacity) {
    if (posture.time <= entries_[0].posture.time) return Push::kStale;
    // Drop the oldest: rotate it to the end, where the new entry is written.
    std::rotate(entries_.begin(), entries_.begin() + 1, entries_.end());
    --count_;
  }

  // Place by capture time: write into the first free slot, then move it back into order.
  int pos = count_;
  Entry& slot = entries_[static_cast<std::size_t>(pos)];
  slot.sequence = sequence;
  slot.posture.time = posture.time;
  slot.posture.root_translation = posture.root_translation;
  slot.posture.rotations.assign(posture.rotations.begin(), posture.rotations.end());
  slot.posture.translations.clear();
  ++count_;
  while (pos > 0 && entries_[static_cast<std::size_t>(pos - 1)].posture.time > posture.time) {
    std::swap(entries_[static_cast<std::size_t>(pos - 1)], entries_[static_cast<std::size_t>(pos)]);
    --pos;
  }
  return Push::kAccepted;
}

bool JitterBuffer::sample(double t, Posture& out) const {
  return sampleShown(t, 0.0, out) != Shown::kNone;
}

JitterBuffer::Shown JitterBuffer::classify(double t, double max_extrapolation_s,
                                           double* shown_capture_time) const {
  double shown = t;
  Shown kind = Shown::kInterpolated;
  if (count_ == 0) {
    kind = Shown::kNone;
    shown = 0.0;
  } else if (const double first = entries_[0].posture.time; t < first) {
    kind = Shown::kHeld;
    shown = first;
  } else if (const double last = newestTime(); t > last) {
    // Past the newest: extrapolated within the limit from two distinct postures.
    const bool can_extrapolate =
        count_ >= 2 && max_extrapolation_s > 0.0 &&
        last - entries_[static_cast<std::size_t>(count_ - 2)].posture.time >= kMinExtrapolationSpan;
    kind = can_extrapolate && t - last <= max_extrapolation_s ? Shown::kExtrapolated : Shown::kHeld;
    shown = last;
  }
  if (shown_capture_time != nullptr) *shown_capture_time = shown;
  return kind;
}

JitterBuffer::Shown JitterBuffer::sampleShown(double t, double max_extrapolation_s, Posture& out,
                                              double* shown_capture_time) const {
  const Shown kind = classify(t, max_extrapolation_s, shown_capture_time);
  if (kind == Shown::kNone) return kind;
  const auto copy = [&out](const Posture& p) {
    out.time = p.time;
    out.root_translation = p.root_translation;
    out.rotations.assign(p.rotations.begin(), p.rotations.end());
    out.translations.clear();
  };
  const Posture& first = entries_[0].posture;
  const Posture& last = entries_[static_cast<std::size_t>(count_ - 1)].posture;
  if (t <= first.time) {
    copy(first);
    return kind;
  }
  if (t >= last.time) {
    // Past the newest: continue the last two postures' motion up to the limit, then hold
    // the pose reached there (a held pose without extrapolation is the newest itself).
    const Posture& before =
        count_ >= 2 ? entries_[static_cast<std::size_t>(count_ - 2)].posture : last;
    const double span = last.time - before.time;
    const double ahead = std::min(t - last.time, std::max(max_extrapolation_s, 0.0));
    if (count_ < 2 || span < kMinExtrapolationSpan || ahead <= 0.0 ||
        before.rotations.size() != last.rotations.size()) {
      copy(last);
      return kind;
    }
    blendPostures(before, last, static_cast<float>(1.0 + ahead / span), out);
    out.translations.clear();
    return kind;
  }
  // The pair around t (times ascend; at least two entries here).
  int i = 1;
  while (entries_[static_cast<std::size_t>(i)].posture.time < t) ++i;
  const Posture& a = entries_[static_cast<std::size_t>(i - 1)].posture;
  const Posture& b = entries_[static_cast<std::size_t>(i)].posture;
  if (a.rotations.size() != b.rotations.size()) {
    copy(b);
    return kind;
  }
  const auto fits = [&](int k) {
    return k >= 0 && k < count_ &&
           entries_[static_cast<std::size_t>(k)].posture.rotations.size() == a.rotations.size();
  };
  const Posture* p = fits(i - 2) ? &entries_[static_cast<std::size_t>(i - 2)].posture : nullptr;
  const Posture* n = fits(i + 1) ? &entries_[static_cast<std::size_t>(i + 1)].posture : nullptr;
  hermitePostures(p, a, b, n, t, out);
  out.translations.clear();
  return kind;
}

double JitterBuffer::oldestTime() const { return count_ > 0 ? entries_[0].posture.time : 0.0; }

double JitterBuffer::newestTime() const {
  return count_ > 0 ? entries_[static_cast<std::size_t>(count_ - 1)].posture.time : 0.0;
}

const Posture* JitterBuffer::firstAfter(double t) const {
  for (int i = 0; i < count_; ++i) {
    const Posture& p = entries_[static_cast<std::size_t>(i)].posture;
    if (p.time > t) return &p;
  }
  return nullptr;
}

}  // namespace vistel::net
