#include "common/wire/posture_delta.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include "common/wire/packets.hpp"

namespace vistel::wire {
namespace {

// ----- layout constants (.team/wire-posture-delta.md) -----

constexpr std::uint8_t kKeyFlag = 0x01;  // flags bit 0: keyframe; bits 1-7: delta distance
static_assert(kKeyFlag == kPostureKeyframeFlags);
constexpr int kTimeLengthBits = 5;  // bit length (0..31) of the time step that follows
constexpr int kClassBits = 3;
// Signed width of each root component's step (mm) per root class; class 0: unchanged.
constexpr std::array<int, 8> kRootBits = {0, 3, 5, 7, 9, 11, 13, 17};
// Signed width of each code step of a changed joint per joint class; class 7: raw 32 bits.
constexpr std::array<int, 7> kJointBits = {2, 3, 4, 5, 6, 7, 9};
constexpr int kRawJointClass = 7;
constexpr std::uint32_t kCodeMask = (1u << kQuatComponentBits) - 1u;
constexpr std::size_t kMaxRecordBytes = kMaxPlainDatagramBytes - kClientHeaderBytes;

std::size_t slotOf(std::uint16_t sequence) {
  return static_cast<std::size_t>(sequence % kDeltaHistory);
}

// Does v fit a bits-wide two's complement field?
bool fitsSigned(std::int32_t v, int bits) {
  const std::int32_t lo = -(std::int32_t{1} << (bits - 1));
  const std::int32_t hi = (std::int32_t{1} << (bits - 1)) - 1;
  return v >= lo && v <= hi;
}

std::uint32_t toField(std::int32_t v, int bits) {
  return static_cast<std::uint32_t>(v) & ((bits == 32) ? 0xFFFFFFFFu : ((1u << bits) - 1u));
}

std::int32_t fromField(std::uint32_t field, int bits) {
  const std::uint32_t sign = 1u << (bits - 1);
  return static_cast<std::int32_t>(field ^ sign) - static_cast<std::int32_t>(sign);
}

int bitLength(std::uint32_t v) { return v == 0 ? 0 : 32 - std::countl_zero(v); }

// The three 10-bit component codes of a packed quaternion (bits 2-11, 12-21, 22-31).
std::array<std::int32_t, 3> codesOf(std::uint32_t packed) {
  return {static_cast<std::int32_t>((packed >> 2) & kCodeMask),
          static_cast<std::int32_t>((packed >> 12) & kCodeMask),
          static_cast<std::int32_t>((packed >> 22) & kCodeMask)};
}

// Rotation angle (radians) between two rotations, in double (q and -q are one rotation).
double rotationAngle(const glm::quat& a, const glm::quat& b) {
  const double na =
      std::sqrt(double(a.w) * a.w + double(a.x) * a.x + double(a.y) * a.y + double(a.z) * a.z);
  const double nb =
      std::sqrt(double(b.w) * b.w + double(b.x) * b.x + double(b.y) * b.y + double(b.z) * b.z);
  const double dot =
      (double(a.w) * b.w + double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z) / (na * nb);
  return 2.0 * std::acos(std::min(1.0, std::fabs(dot)));  // NaN stays NaN
}

}  // namespace

// =============================== encoder ===============================

PostureDeltaEncoder::PostureDeltaEncoder(const PostureDeltaOptions& options) : options_(options) {
  options_.joint_count = std::clamp(options_.joint_count, 1, kMaxWireJoints);
  const float max_tol = kQuatAngleBoundRad - 0.01f * 3.14159265f / 180.0f;
  options_.joint_tolerance_rad = std::clamp(options_.joint_tolerance_rad, 0.0f, max_tol);
  options_.root_tolerance_m = std::clamp(options_.root_tolerance_m, 0.0f, kRootUnit);
  if (!(options_.key_interval_s >= 1e-3)) options_.key_interval_s = 1e-3;
  if (!(options_.key_retry_s >= 0.0)) options_.key_retry_s = 0.0;
  codes_.assign(static_cast<std::size_t>(kDeltaHistory * options_.joint_count), 0u);
  scratch_.reserve(kMaxRecordBytes);
}

void PostureDeltaEncoder::reset() {
  for (Slot& s : slots_) s.valid = false;
  have_newest_ = have_key_ = have_ack_ = false;
  key_requested_ = true;
}

bool PostureDeltaEncoder::encode(const Posture& posture, std::uint16_t sequence,
                                 double capture_time, bool force_key,
                                 std::vector<std::uint8_t>& out, DeltaFrameInfo* info) {
  if (posture.rotations.size() != static_cast<std::size_t>(options_.joint_count)) return false;
  if (!encodePostureRecord(posture, sequence, capture_time, current_)) return false;
  return encodeRecord(&posture, force_key, out, info);
}

bool PostureDeltaEncoder::encode(const PostureRecord& record, bool force_key,
                                 std::vector<std::uint8_t>& out, DeltaFrameInfo* info) {
  if (record.joint_count != options_.joint_count) return false;
  current_.sequence = record.sequence;
  current_.time = record.time;
  current_.root_mm = record.root_mm;
  current_.joint_count = record.joint_count;
  std::copy_n(record.rotations.begin(), record.joint_count, current_.rotations.begin());
  return encodeRecord(nullptr, force_key, out, info);
}

void PostureDeltaEncoder::acknowledge(std::uint16_t sequence) {
  const Slot& s = slots_[slotOf(sequence)];
  if (!s.valid || s.sequence != sequence) return;
  if (!have_ack_ || sequenceNewer(sequence, newest_ack_)) {
    newest_ack_ = sequence;
    have_ack_ = true;
  }
}

// Empties the slots of the sequences skipped between the newest and this one (so that a slot
// never holds a sequence more than kDeltaHistory - 1 behind the newest).
void PostureDeltaEncoder::advanceTo(std::uint16_t sequence) {
  if (!have_newest_) {
    have_newest_ = true;
    newest_ = sequence;
    return;
  }
  if (!sequenceNewer(sequence, newest_)) return;
  const auto gap = static_cast<std::uint16_t>(sequence - newest_);
  if (gap >= kDeltaHistory) {
    for (Slot& s : slots_) s.valid = false;
  } else {
    for (std::uint16_t k = 1; k < gap; ++k) slots_[slotOf(newest_ + k)].valid = false;
  }
  newest_ = sequence;
}

int PostureDeltaEncoder::chooseReference(std::uint16_t sequence, std::uint32_t time) const {
  const auto usable = [&](bool have, std::uint16_t ref) {
    if (!have) return -1;
    const auto distance = static_cast<std::uint16_t>(sequence - ref);
    if (distance < 1 || distance >= kDeltaHistory) return -1;
    const Slot& s = slots_[slotOf(ref)];
    return s.valid && s.sequence == ref ? static_cast<int>(slotOf(ref)) : -1;
  };
  switch (options_.reference) {
    case DeltaReference::kPrevious:
      return usable(have_newest_, static_cast<std::uint16_t>(sequence - 1));
    case DeltaReference::kKeyframe:
      return usable(have_key_, last_key_);
    case DeltaReference::kAcked: {
      const int acked = usable(have_ack_, newest_ack_);
      if (acked >= 0) return acked;
      const auto key_age = static_cast<std::int32_t>(time - last_key_ticks_);
      const auto retry = static_cast<std::int64_t>(options_.key_retry_s / kWireTimeTick);
      return key_age >= 0 && key_age < retry ? usable(have_key_, last_key_) : -1;
    }
  }
  return -1;
}

void PostureDeltaEncoder::store(int slot) {
  Slot& s = slots_[static_cast<std::size_t>(slot)];
  s.valid = true;
  s.sequence = current_.sequence;
  s.time = current_.time;
  s.root_mm = current_.root_mm;
  std::copy_n(current_.rotations.begin(), options_.joint_count,
              codes_.begin() + static_cast<std::ptrdiff_t>(slot) * options_.joint_count);
}

bool PostureDeltaEncoder::encodeRecord(const Posture* truth, bool force_key,
                                       std::vector<std::uint8_t>& out, DeltaFrameInfo* info) {
  const std::uint16_t seq = current_.sequence;
  const int n = options_.joint_count;
  const auto nu = static_cast<std::size_t>(n);

  // A frame with a sequence at or behind the newest (a caller's restart) starts over.
  if (have_newest_ && !sequenceNewer(seq, newest_)) reset();
  advanceTo(seq);

  // Keyframe due? (forced, requested, first, interval, or no usable reference)
  const auto interval_ticks = static_cast<std::int64_t>(options_.key_interval_s / kWireTimeTick);
  const auto since_key = static_cast<std::int32_t>(current_.time - last_key_ticks_);
  bool key =
      force_key || key_requested_ || !have_key_ || since_key < 0 || since_key >= interval_ticks;
  const int ref_slot = key ? -1 : chooseReference(seq, current_.time);
  if (ref_slot < 0) key = true;

  // The delta candidate: joints (and root components) within the tolerance of the reference
  // keep its codes, so current_ becomes what the decoder will reconstruct.
  int changed = 0;
  if (!key) {
    const Slot& slot = slots_[static_cast<std::size_t>(ref_slot)];
    reference_.sequence = slot.sequence;
    reference_.time = slot.time;
    reference_.root_mm = slot.root_mm;
    reference_.joint_count = static_cast<std::uint8_t>(n);
    std::copy_n(codes_.begin() + static_cast<std::ptrdiff_t>(ref_slot) * n, n,
                reference_.rotations.begin());
    if (truth != nullptr) {
      for (std::size_t k = 0; k < 3; ++k) {
        const float ref_m = static_cast<float>(reference_.root_mm[k]) * kRootUnit;
        if (std::fabs(ref_m - truth->root_translation[static_cast<int>(k)]) <=
            options_.root_tolerance_m) {
          current_.root_mm[k] = reference_.root_mm[k];
        }
      }
      for (std::size_t j = 0; j < nu; ++j) {
        const std::uint32_t r = reference_.rotations[j];
        if (current_.rotations[j] != r && options_.joint_tolerance_rad > 0.0f &&
            rotationAngle(unpackQuat(r), truth->rotations[j]) <= options_.joint_tolerance_rad) {
          current_.rotations[j] = r;
        }
      }
    }
    for (std::size_t j = 0; j < nu; ++j) {
      changed += current_.rotations[j] != reference_.rotations[j] ? 1 : 0;
    }
    scratch_.clear();
    // No delta (time went back), or one no smaller than a keyframe: send the keyframe.
    if (appendPostureDelta(current_, reference_, scratch_) == 0 ||
        scratch_.size() >= static_cast<std::size_t>(deltaKeyframeBytes(n))) {
      key = true;
    }
  }

  // Emit the keyframe (the exact codes: the reconstruction is the quantized record) or the delta.
  const std::size_t before = out.size();
  if (key) {
    if (truth != nullptr) {
      const std::uint32_t time = current_.time;
      encodePostureRecord(*truth, seq, 0.0, current_);
      current_.time = time;
    }
    appendPostureKeyframe(current_, out);
    have_key_ = true;
    last_key_ = seq;
    last_key_ticks_ = current_.time;
    key_requested_ = false;
    changed = n;
  } else {
    out.insert(out.end(), scratch_.begin(), scratch_.end());
  }
  store(static_cast<int>(slotOf(seq)));

  if (info != nullptr) {
    info->keyframe = key;
    info->sequence = seq;
    info->reference = key ? seq : reference_.sequence;
    info->changed_joints = changed;
    info->bytes = static_cast<int>(out.size() - before);
  }
  return true;
}

// =========================== stateless writers ===========================

std::size_t appendPostureKeyframe(const PostureRecord& record, std::vector<std::uint8_t>& out) {
  const std::size_t before = out.size();
  // Flags, then the §3.3 record field by field (what serialize(PostureRecord) writes).
  out.push_back(kKeyFlag);
  WriteStream w(out);
  std::uint32_t v = record.sequence;
  w.bits(v, 16);
  v = record.time;
  w.bits(v, 32);
  v = record.joint_count;
  w.bits(v, 8);
  for (std::int16_t c : record.root_mm) {
    v = static_cast<std::uint16_t>(c);
    w.bits(v, 16);
  }
  for (std::size_t j = 0; j < record.joint_count; ++j) {
    v = record.rotations[j];
    w.bits(v, kQuatBits);
  }
  return out.size() - before;
}

std::size_t appendPostureDelta(const PostureRecord& current, const PostureRecord& reference,
                               std::vector<std::uint8_t>& out) {
  const auto distance = static_cast<std::uint16_t>(current.sequence - reference.sequence);
  const std::uint32_t dt = current.time - reference.time;
  if (current.joint_count != reference.joint_count || current.joint_count == 0 || distance < 1 ||
      distance >= kDeltaHistory || dt >= 0x80000000u) {
    return 0;
  }
  const std::size_t before = out.size();
  WriteStream w(out);
  // Flags (distance to the reference), sequence.
  std::uint32_t flags = static_cast<std::uint32_t>(distance) << 1;
  w.bits(flags, 8);
  std::uint32_t seq_field = current.sequence;
  w.bits(seq_field, 16);
  // Time step: its bit length, then its bits.
  std::uint32_t len = static_cast<std::uint32_t>(bitLength(dt));
  w.bits(len, kTimeLengthBits);
  std::uint32_t dt_field = dt;
  if (len > 0) w.bits(dt_field, static_cast<int>(len));
  // Root: one class (width) for the three steps, the narrowest that holds them.
  std::array<std::int32_t, 3> root_step{};
  for (std::size_t k = 0; k < 3; ++k) {
    root_step[k] = std::int32_t{current.root_mm[k]} - std::int32_t{reference.root_mm[k]};
  }
  std::uint32_t root_class = 0;
  if (root_step != std::array<std::int32_t, 3>{}) {
    root_class = 1;
    while (root_class < 7 && !std::all_of(root_step.begin(), root_step.end(), [&](std::int32_t v) {
             return fitsSigned(v, kRootBits[root_class]);
           })) {
      ++root_class;
    }
  }
  w.bits(root_class, kClassBits);
  if (root_class > 0) {
    for (std::int32_t v : root_step) {
      std::uint32_t field = toField(v, kRootBits[root_class]);
      w.bits(field, kRootBits[root_class]);
    }
  }
  // Joints: a changed bit, then a class and the three code steps (or the raw 32 bits).
  for (std::size_t j = 0; j < current.joint_count; ++j) {
    std::uint32_t c = current.rotations[j];
    const std::uint32_t r = reference.rotations[j];
    std::uint32_t changed_bit = c == r ? 0u : 1u;
    w.bits(changed_bit, 1);
    if (c == r) continue;
    std::uint32_t cls = kRawJointClass;
    std::array<std::int32_t, 3> step{};
    if ((c & 3u) == (r & 3u)) {
      const auto cc = codesOf(c);
      const auto rc = codesOf(r);
      for (std::size_t k = 0; k < 3; ++k) step[k] = cc[k] - rc[k];
      for (std::uint32_t k = 0; k < kJointBits.size(); ++k) {
        const int b = kJointBits[k];
        if (fitsSigned(step[0], b) && fitsSigned(step[1], b) && fitsSigned(step[2], b)) {
          cls = k;
          break;
        }
      }
    }
    w.bits(cls, kClassBits);
    if (cls == kRawJointClass) {
      w.bits(c, 32);
    } else {
      for (std::int32_t v : step) {
        std::uint32_t field = toField(v, kJointBits[cls]);
        w.bits(field, kJointBits[cls]);
      }
    }
  }
  w.align();
  return out.size() - before;
}

// =============================== decoder ===============================

PostureDeltaDecoder::PostureDeltaDecoder(int joint_count)
    : joint_count_(std::clamp(joint_count, 1, kMaxWireJoints)) {
  codes_.assign(static_cast<std::size_t>(kDeltaHistory * joint_count_), 0u);
}

void PostureDeltaDecoder::reset() {
  for (Slot& s : slots_) s.valid = false;
  have_newest_ = false;
}

void PostureDeltaDecoder::store(const PostureRecord& record) {
  const std::uint16_t seq = record.sequence;
  // Advance the window: empty the slots of skipped sequences; an old frame behind the window
  // is not kept (no later delta can name it).
  if (!have_newest_) {
    have_newest_ = true;
    newest_ = seq;
  } else if (sequenceNewer(seq, newest_)) {
    const auto gap = static_cast<std::uint16_t>(seq - newest_);
    if (gap >= kDeltaHistory) {
      for (Slot& s : slots_) s.valid = false;
    } else {
      for (std::uint16_t k = 1; k < gap; ++k) slots_[slotOf(newest_ + k)].valid = false;
    }
    newest_ = seq;
  } else if (static_cast<std::uint16_t>(newest_ - seq) >= kDeltaHistory) {
    return;
  }
  const std::size_t slot = slotOf(seq);
  Slot& s = slots_[slot];
  s.valid = true;
  s.sequence = seq;
  s.time = record.time;
  s.root_mm = record.root_mm;
  std::copy_n(record.rotations.begin(), joint_count_,
              codes_.begin() + static_cast<std::ptrdiff_t>(slot) * joint_count_);
}

bool PostureDeltaDecoder::held(std::uint16_t sequence, PostureRecord& out) const {
  const std::size_t slot = slotOf(sequence);
  const Slot& s = slots_[slot];
  if (!s.valid || s.sequence != sequence) return false;
  out.sequence = sequence;
  out.time = s.time;
  out.root_mm = s.root_mm;
  out.joint_count = static_cast<std::uint8_t>(joint_count_);
  std::copy_n(codes_.begin() + static_cast<std::ptrdiff_t>(slot) * joint_count_, joint_count_,
              out.rotations.begin());
  return true;
}

DeltaDecodeResult PostureDeltaDecoder::decode(std::span<const std::uint8_t> bytes,
                                              PostureRecord& out) {
  DeltaDecodeResult res;
  const auto malformed = [&](const char* why) {
    res.status = DeltaStatus::kMalformed;
    res.reason = why;
    return res;
  };
  if (bytes.size() < 3) return malformed("record shorter than its 3-byte head");
  if (bytes.size() > kMaxRecordBytes) return malformed("record longer than a datagram allows");
  const std::uint8_t flags = bytes[0];
  res.sequence = static_cast<std::uint16_t>(bytes[1] | (bytes[2] << 8));
  res.keyframe = (flags & kKeyFlag) != 0;

  // Keyframe: the §3.3 record after the flags byte.
  if (res.keyframe) {
    if (flags != kKeyFlag) return malformed("keyframe flags: reserved bits 1-7 set");
    ReadStream r(bytes.subspan(1));
    if (!serialize(r, out) || !r.atEnd()) {
      return malformed("keyframe length does not match its joint count");
    }
    if (out.joint_count != joint_count_)
      return malformed("keyframe joint count is not the avatar's");
    res.reference = res.sequence;
    // A keyframe far behind the newest is a sender that started over, not a late datagram:
    // follow it (else its deltas would name frames too old to keep, and be refused until the
    // sequence caught up).
    if (have_newest_ && !sequenceNewer(res.sequence, newest_) &&
        static_cast<std::uint16_t>(newest_ - res.sequence) >= kDeltaRestartDistance) {
      reset();
    }
    store(out);
    return res;
  }

  // Delta: the reference must be held.
  const int distance = flags >> 1;
  if (distance < 1 || distance >= kDeltaHistory) return malformed("delta distance outside 1..63");
  res.reference = static_cast<std::uint16_t>(res.sequence - distance);
  const std::size_t ref_slot = slotOf(res.reference);
  const Slot& ref = slots_[ref_slot];
  if (!ref.valid || ref.sequence != res.reference) {
    res.status = DeltaStatus::kMissingReference;
    res.reason = "delta reference not held";
    return res;
  }
  const std::uint32_t* ref_codes =
      codes_.data() + static_cast<std::ptrdiff_t>(ref_slot) * joint_count_;

  ReadStream r(bytes.subspan(3));
  out.sequence = res.sequence;
  out.joint_count = static_cast<std::uint8_t>(joint_count_);
  // Time step.
  std::uint32_t len = 0;
  if (!r.bits(len, kTimeLengthBits)) return malformed("delta truncated in the time step");
  std::uint32_t dt = 0;
  if (len > 0 && !r.bits(dt, static_cast<int>(len))) {
    return malformed("delta truncated in the time step");
  }
  out.time = ref.time + dt;
  // Root.
  std::uint32_t root_class = 0;
  if (!r.bits(root_class, kClassBits)) return malformed("delta truncated in the root class");
  for (std::size_t k = 0; k < 3; ++k) {
    std::int32_t step = 0;
    const int b = kRootBits[root_class];
    if (b > 0) {
      std::uint32_t field = 0;
      if (!r.bits(field, b)) return malformed("delta truncated in the root");
      step = fromField(field, b);
    }
    const std::int32_t v = std::int32_t{ref.root_mm[k]} + step;
    if (v < -32767 || v > 32767) return malformed("delta root outside +-32767 mm");
    out.root_mm[k] = static_cast<std::int16_t>(v);
  }
  // Joints.
  for (int j = 0; j < joint_count_; ++j) {
    const auto ju = static_cast<std::size_t>(j);
    const std::uint32_t rc = ref_codes[ju];
    std::uint32_t changed = 0;
    if (!r.bits(changed, 1)) return malformed("delta truncated in the joints");
    if (changed == 0) {
      out.rotations[ju] = rc;
      continue;
    }
    std::uint32_t cls = 0;
    if (!r.bits(cls, kClassBits)) return malformed("delta truncated in the joints");
    if (cls == kRawJointClass) {
      if (!r.bits(out.rotations[ju], 32)) return malformed("delta truncated in the joints");
      continue;
    }
    const int b = kJointBits[cls];
    const auto base = codesOf(rc);
    std::uint32_t packed = rc & 3u;
    for (int k = 0; k < 3; ++k) {
      std::uint32_t field = 0;
      if (!r.bits(field, b)) return malformed("delta truncated in the joints");
      const std::int32_t v = base[static_cast<std::size_t>(k)] + fromField(field, b);
      if (v < 0 || v > static_cast<std::int32_t>(kCodeMask)) {
        return malformed("delta joint code outside 0..1023");
      }
      packed |= static_cast<std::uint32_t>(v) << (2 + k * kQuatComponentBits);
    }
    out.rotations[ju] = packed;
  }
  if (!r.align()) return malformed("delta padding bits not zero");
  if (!r.atEnd()) return malformed("delta has bytes after its last joint");
  store(out);
  return res;
}

// =============================== forwarding ===============================

std::size_t appendForwardedPosture(const PostureDeltaDecoder& sender_history,
                                   const PostureRecord& current, const PostureDeltaOptions& options,
                                   DeltaForwardState& state, PostureRecord& scratch,
                                   std::vector<std::uint8_t>& out) {
  const auto ticks = [](double s) {
    return static_cast<std::int64_t>(std::max(s, 0.0) / kWireTimeTick);
  };
  const auto since_key = static_cast<std::int32_t>(current.time - state.last_key_time);
  const bool key_due = state.key_requested || !state.have_key || since_key < 0 ||
                       since_key >= std::max<std::int64_t>(ticks(options.key_interval_s), 10);
  if (!key_due) {
    // The acknowledged frame, else the last keyframe sent while young, if the history holds it.
    const bool ack_ok = state.have_ack && state.acked != current.sequence &&
                        sender_history.held(state.acked, scratch);
    const bool key_ok = !ack_ok && since_key < ticks(options.key_retry_s) &&
                        state.last_key != current.sequence &&
                        sender_history.held(state.last_key, scratch);
    if (ack_ok || key_ok) {
      const std::size_t before = out.size();
      const std::size_t n = appendPostureDelta(current, scratch, out);
      if (n > 0 && n < static_cast<std::size_t>(deltaKeyframeBytes(current.joint_count))) {
        return n;
      }
      out.resize(before);  // no usable delta: a keyframe instead
    }
  }
  state.have_key = true;
  state.last_key = current.sequence;
  state.last_key_time = current.time;
  state.key_requested = false;
  return appendPostureKeyframe(current, out);
}

}  // namespace vistel::wire
