// Delta coding of one sender's posture stream (draft wire format: .team/wire-posture-delta.md;
// not yet in proto/WIRE.md): keyframes carry the full quantized record of §3.3; delta frames
// carry only what changed against a reference frame the receiver holds, in the quantized code
// space of §3.3, with a variable width per joint.
//
// Precision: the same as §3.3. A decoded joint rotation is either the sender's own packQuat
// code (at most 0.227 degrees from the sent rotation) or, when the encoder was given the true
// Posture, the reference's code kept because it is within `joint_tolerance_rad` (default 0.2
// degrees) of the sent rotation. Either way every decoded rotation is within kQuatAngleBoundRad
// (0.25 degrees) of what was sent, and the root within 1 mm. Encoder and decoder reconstruct
// the same codes bit for bit (the encoder keeps what the decoder will hold), so nothing drifts.
//
// References (what a delta is against): the newest frame the receiver acknowledged
// (acknowledge(); kAcked, the default) while it is at most kDeltaHistory - 1 frames old, else
// the newest keyframe while it is younger than key_retry_s, else a new keyframe; a lost datagram
// then costs that frame only, and a lost keyframe costs nothing once acknowledgements flow (at
// most key_retry_s before). Measured in bench/wire. Without acknowledgements (kKeyframe), a lost
// keyframe costs the deltas against it until the next keyframe. kPrevious (each delta against the
// frame before) is the most compact and the least robust: for measurement only.
//
// Cost: O(joints) per frame; no allocation after construction (the encoder appends to the
// caller's vector, which allocates only when it lacks capacity). Not thread-safe.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "common/anim/posture.hpp"
#include "common/wire/posture_codec.hpp"

namespace vistel::wire {

// Frames each side keeps (encoder: what it sent; decoder: what it decoded); a delta's
// reference is 1..kDeltaHistory - 1 sequence numbers before it.
inline constexpr int kDeltaHistory = 64;
// A keyframe at least this far behind the decoder's newest frame (about 1 s at 60 Hz) restarts
// the decoder's history: a sender that started over (a datagram that late is rare, and costs a
// key interval at most). So every frame decoded is also held: acknowledge every kOk frame.
inline constexpr int kDeltaRestartDistance = kDeltaHistory;
// Bytes of a keyframe record of n joints: flags, sequence, then the §3.3 fields after it.
constexpr int deltaKeyframeBytes(int joint_count) { return 1 + postureRecordBytes(joint_count); }

enum class DeltaReference : std::uint8_t {
  kAcked,     // the newest acknowledged frame, else the newest keyframe (default)
  kKeyframe,  // always the newest keyframe
  kPrevious,  // the previous frame (no loss tolerance: measurement only)
};

struct PostureDeltaOptions {
  int joint_count = 52;         // joints of the sender's avatar (1..kMaxWireJoints)
  double key_interval_s = 0.5;  // a keyframe at least this often (capture time); > 0
  // kAcked: deltas fall back on the newest keyframe only while it is younger than this (capture
  // time); past it, with still no usable acknowledgement, a new keyframe is sent (the last one
  // may have been lost). 0.2 s: above a round trip plus a tick.
  double key_retry_s = 0.2;
  DeltaReference reference = DeltaReference::kAcked;
  // encode(const Posture&): a joint whose reference rotation (decoded) is within this angle
  // of the posture's keeps the reference's code (sent as "unchanged"); 0 sends every changed
  // code. At most kQuatAngleBoundRad - 0.01 degrees (larger values are clamped to it).
  float joint_tolerance_rad = 0.2f * 3.14159265f / 180.0f;
  // The same for each root component (metres); at most 0.001 (the stated root precision).
  float root_tolerance_m = 0.0009f;
};

// What a frame was: for statistics and tests.
struct DeltaFrameInfo {
  bool keyframe = false;
  std::uint16_t sequence = 0;
  std::uint16_t reference = 0;  // the reference's sequence (deltas only)
  int changed_joints = 0;       // joints sent (keyframes: all)
  int bytes = 0;                // record bytes appended
};

// One frame of a history (encoder or decoder) but its rotations: which sequence the slot
// holds, its time and root; the rotation codes sit in a flat array beside the slots.
struct DeltaHistorySlot {
  bool valid = false;
  std::uint16_t sequence = 0;
  std::uint32_t time = 0;
  std::array<std::int16_t, 3> root_mm{};
};

class PostureDeltaEncoder {
 public:
  // Options are clamped into range (joint_count to 1..255, tolerances to their maxima,
  // key_interval_s to at least 1 ms).
  explicit PostureDeltaEncoder(const PostureDeltaOptions& options = {});

  // Quantizes the posture (§3.3) and appends one record (keyframe or delta) to out. A keyframe
  // when force_key, when one was requested, when none was sent yet, every key_interval_s of
  // capture time, when no reference is in the history, or when it is not larger than the
  // delta. False (nothing appended) when the posture's joint count is not options.joint_count.
  // Sequence: +1 per call (wraps); the caller owns it (other values work, but a jump empties
  // the history, as it does the decoder's).
  bool encode(const Posture& posture, std::uint16_t sequence, double capture_time, bool force_key,
              std::vector<std::uint8_t>& out, DeltaFrameInfo* info = nullptr);
  // The same for a record already quantized (a decoded one being forwarded): exact, no
  // tolerance (a joint is unchanged only when its code is equal). record.sequence and
  // record.time are sent as they are.
  bool encode(const PostureRecord& record, bool force_key, std::vector<std::uint8_t>& out,
              DeltaFrameInfo* info = nullptr);

  // The receiver holds frame `sequence` (it decoded it). Ignored unless that frame is still in
  // the history. Acknowledgements may arrive late, twice or out of order.
  void acknowledge(std::uint16_t sequence);
  // The next frame will be a keyframe (a receiver said kMissingReference, or a new one joined).
  void requestKeyframe() { key_requested_ = true; }
  // Forgets everything: the next frame is a keyframe, acknowledgements start over.
  void reset();

  // The record the decoder reconstructs from the last frame encoded (tests, forwarding).
  const PostureRecord& lastReconstructed() const { return current_; }
  const PostureDeltaOptions& options() const { return options_; }

 private:
  using Slot = DeltaHistorySlot;
  bool encodeRecord(const Posture* truth, bool force_key, std::vector<std::uint8_t>& out,
                    DeltaFrameInfo* info);
  int chooseReference(std::uint16_t sequence, std::uint32_t time) const;  // slot index, or -1
  void advanceTo(std::uint16_t sequence);
  void store(int slot);

  PostureDeltaOptions options_;
  std::array<Slot, kDeltaHistory> slots_{};
  std::vector<std::uint32_t> codes_;  // (kDeltaHistory * joint_count) packed rotations per slot
  bool have_newest_ = false;
  std::uint16_t newest_ = 0;
  bool have_key_ = false;
  std::uint16_t last_key_ = 0;
  std::uint32_t last_key_ticks_ = 0;  // wire capture time of that keyframe
  bool have_ack_ = false;
  std::uint16_t newest_ack_ = 0;
  bool key_requested_ = true;
  PostureRecord current_;              // the frame being encoded, then as reconstructed
  PostureRecord reference_;            // the delta's reference (a copy of its slot)
  std::vector<std::uint8_t> scratch_;  // the delta candidate (capacity reserved)
};

// Stateless writers (what PostureDeltaEncoder uses; for a forwarder that keeps one history per
// sender and, per receiver, only which frames it acknowledged). Both append to out and return
// the bytes appended. appendPostureDelta is exact (codes equal to the reference's are
// "unchanged", others are sent as they are) and returns 0, appending nothing, when it cannot
// express current against reference: different joint counts, a sequence distance outside
// 1..kDeltaHistory - 1, or a time step outside 0..2^31 - 1 ticks.
std::size_t appendPostureKeyframe(const PostureRecord& record, std::vector<std::uint8_t>& out);
std::size_t appendPostureDelta(const PostureRecord& current, const PostureRecord& reference,
                               std::vector<std::uint8_t>& out);

enum class DeltaStatus : std::uint8_t {
  kOk,
  kMissingReference,  // a delta whose reference this decoder does not hold: dropped
  kMalformed,         // bytes that are not one valid record (reason says why): dropped
};

struct DeltaDecodeResult {
  DeltaStatus status = DeltaStatus::kOk;
  const char* reason = "";  // static text naming the field and the fault; "" when kOk
  bool keyframe = false;
  std::uint16_t sequence = 0;   // valid from the first 3 bytes on (also for kMissingReference)
  std::uint16_t reference = 0;  // deltas: the reference's sequence
  bool ok() const { return status == DeltaStatus::kOk; }
};

class PostureDeltaDecoder {
 public:
  // joint_count: the sender's avatar's (1..255, clamped); a keyframe with another count is
  // malformed.
  explicit PostureDeltaDecoder(int joint_count = 52);

  // Decodes exactly one record (the whole span: a byte short or over is malformed). On kOk out
  // holds the frame (any sequence, also an older one: newest-wins is the caller's rule) and
  // the frame becomes a reference for later deltas (a keyframe kDeltaRestartDistance or more
  // behind the newest first empties the history); otherwise out is unspecified and the
  // history is unchanged. Never reads past the span; any byte string is safe.
  DeltaDecodeResult decode(std::span<const std::uint8_t> bytes, PostureRecord& out);
  // Forgets every frame (a new session of the sender: its sequences start over).
  void reset();
  // Copies the held frame `sequence` into out (the reference a forwarding encoder deltas
  // against); false when it is not held.
  bool held(std::uint16_t sequence, PostureRecord& out) const;

 private:
  using Slot = DeltaHistorySlot;
  void store(const PostureRecord& record);

  int joint_count_ = 52;
  std::array<Slot, kDeltaHistory> slots_{};
  std::vector<std::uint32_t> codes_;  // (kDeltaHistory * joint_count) packed rotations per slot
  bool have_newest_ = false;
  std::uint16_t newest_ = 0;
};

// Forwarding (server -> recipients): the sender's uplink decoder is the sender's history; per
// (recipient, sender) a forwarder keeps only this. Same reference rule as kAcked: the newest
// frame the recipient acknowledged while the sender's history still holds it, else the last
// keyframe sent to the recipient while it is younger than key_retry_s (and held), else a
// keyframe; a keyframe also every key_interval_s of capture time and on request.
struct DeltaForwardState {
  bool have_ack = false;
  std::uint16_t acked = 0;  // newest sequence (sender's numbering) the recipient decoded
  bool have_key = false;
  std::uint16_t last_key = 0;
  std::uint32_t last_key_time = 0;  // wire time of that keyframe
  bool key_requested = true;        // the first frame is a keyframe

  // The recipient decoded frame `sequence` of this sender (newer ones win; older ignored).
  void acknowledge(std::uint16_t sequence) {
    if (!have_ack || sequenceNewer(sequence, acked)) {
      acked = sequence;
      have_ack = true;
    }
  }
};

// Appends `current` (a frame the sender's history holds, normally the newest) for one recipient:
// a delta against the reference above or a keyframe (options: key_interval_s, key_retry_s);
// returns the bytes appended and updates the state. `scratch` is working space for the reference
// (any record; overwritten). Exact: the recipient decodes `current` bit for bit. No allocation
// beyond out's growth.
std::size_t appendForwardedPosture(const PostureDeltaDecoder& sender_history,
                                   const PostureRecord& current, const PostureDeltaOptions& options,
                                   DeltaForwardState& state, PostureRecord& scratch,
                                   std::vector<std::uint8_t>& out);

}  // namespace vistel::wire
