// The adaptive playout buffer. Delay from a percentile of arrival - capture offsets (the
// approach of Ramjee et al. 1994 and of WebRTC's NetEq, in a simpler form); talkspurt
// re-alignment in silence; one-frame drop/insert inside a talkspurt for drift.
#include "common/voice/jitter_buffer.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace vistel {

VoiceJitterBuffer::VoiceJitterBuffer(const JitterBufferSettings& settings) : settings_(settings) {
  assert(settings_.capacity >= 4 && settings_.window_packets >= 1);
  slots_.resize(static_cast<size_t>(settings_.capacity));
  offsets_.assign(static_cast<size_t>(settings_.window_packets), 0);
  scratch_.assign(static_cast<size_t>(settings_.window_packets), 0);
}

VoiceJitterBuffer::Slot* VoiceJitterBuffer::find(int64_t sequence) {
  const int64_t capacity = settings_.capacity;
  Slot& slot = slots_[static_cast<size_t>(((sequence % capacity) + capacity) % capacity)];
  return slot.used && slot.sequence == sequence ? &slot : nullptr;
}

VoiceJitterBuffer::Slot* VoiceJitterBuffer::earliest() {
  Slot* best = nullptr;
  for (Slot& slot : slots_) {
    if (slot.used && (!best || slot.sequence < best->sequence)) best = &slot;
  }
  return best;
}

void VoiceJitterBuffer::recordOffset(int64_t offset) {
  // The window's ring.
  offsets_[offsets_next_] = offset;
  offsets_next_ = (offsets_next_ + 1) % offsets_.size();
  offsets_count_ = std::min(offsets_count_ + 1, offsets_.size());
  // Its minimum and percentile (nth_element on a copy): at once when this packet was later
  // than the target (jitter rising) or the window is young, else every 8th packet.
  const bool rising = offset + settings_.margin_samples > target_offset_;
  if (!rising && offsets_count_ == offsets_.size() && ++since_update_ < 8) return;
  since_update_ = 0;
  std::copy_n(offsets_.begin(), offsets_count_, scratch_.begin());
  const auto end = scratch_.begin() + static_cast<std::ptrdiff_t>(offsets_count_);
  min_offset_ = *std::min_element(scratch_.begin(), end);
  const auto rank = static_cast<std::ptrdiff_t>(
      std::floor(settings_.percentile * static_cast<double>(offsets_count_ - 1) + 0.5));
  std::nth_element(scratch_.begin(), scratch_.begin() + rank, end);
  const int64_t quantile = scratch_[static_cast<size_t>(rank)];
  target_offset_ =
      std::min(quantile + settings_.margin_samples, min_offset_ + settings_.max_delay_samples);
}

bool VoiceJitterBuffer::push(const VoicePacketView& packet, int64_t arrival_time) {
  if (packet.payload.empty() || packet.payload.size() > static_cast<size_t>(kVoiceMaxPacketBytes)) {
    ++stats_.invalid;
    return false;
  }
  // Extend the wrapping sequence and capture time against the newest seen.
  int64_t sequence = packet.sequence;
  int64_t capture = packet.capture_time;
  if (have_reference_) {
    sequence = newest_sequence_ + static_cast<int16_t>(static_cast<uint16_t>(
                                      packet.sequence - static_cast<uint16_t>(newest_sequence_)));
    capture = newest_capture_ +
              static_cast<int32_t>(packet.capture_time - static_cast<uint32_t>(newest_capture_));
  }
  if (!have_reference_ || sequence > newest_sequence_) {
    newest_sequence_ = sequence;
    newest_capture_ = capture;
  }
  have_reference_ = true;

  // Duplicates are dropped before they count twice in the statistics.
  if (find(sequence) != nullptr) {
    ++stats_.duplicate;
    return true;
  }
  recordOffset(arrival_time - capture);
  if (have_horizon_ && sequence < next_sequence_) {
    ++stats_.late;
    return true;
  }
  if (have_horizon_ && sequence >= next_sequence_ + settings_.capacity) {
    ++stats_.too_far;
    return true;
  }
  // Store it; an older packet still in its slot is stale (never played) and goes.
  const int64_t capacity = settings_.capacity;
  Slot& slot = slots_[static_cast<size_t>(((sequence % capacity) + capacity) % capacity)];
  if (slot.used) {
    if (slot.sequence > sequence) {
      ++stats_.too_far;
      return true;
    }
    ++stats_.dropped;
  }
  slot.used = true;
  slot.sequence = sequence;
  slot.capture_time = capture;
  slot.size = static_cast<uint16_t>(packet.payload.size());
  std::copy(packet.payload.begin(), packet.payload.end(), slot.bytes.begin());
  ++stats_.received;
  return true;
}

PlayoutDecision VoiceJitterBuffer::emit(PlayoutKind kind, const Slot* slot, int64_t capture,
                                        int64_t sequence) {
  PlayoutDecision decision;
  decision.kind = kind;
  decision.capture_time = capture;
  decision.sequence = sequence;
  if (slot != nullptr) {
    std::copy_n(slot->bytes.begin(), slot->size, out_packet_.begin());
    decision.packet = std::span<const uint8_t>(out_packet_.data(), slot->size);
  }
  return decision;
}

PlayoutDecision VoiceJitterBuffer::pull(int64_t now) {
  const int64_t frame = kVoiceFrameSamples;
  if (!have_reference_) {
    ++stats_.silence;
    return {};
  }
  // At most twice: a talkspurt that ends here falls through to the start of the next.
  for (int pass = 0; pass < 2; ++pass) {
    if (!playing_) {
      // Between talkspurts: start at the earliest buffered packet once it is due, skipping
      // packets already a frame late when the one after them is due too.
      Slot* first = earliest();
      while (first != nullptr && now - first->capture_time - target_offset_ >= frame) {
        Slot* after = find(first->sequence + 1);
        if (after == nullptr || now - after->capture_time < target_offset_) break;
        first->used = false;
        ++stats_.dropped;
        first = after;
      }
      if (first == nullptr || now - first->capture_time < target_offset_) {
        ++stats_.silence;
        return {};
      }
      playing_ = true;
      have_horizon_ = true;
      next_sequence_ = first->sequence;
      play_capture_ = first->capture_time;
      missing_run_ = 0;
      ++stats_.talkspurts;
    }

    // A packet that follows in sequence but jumps in time starts a new talkspurt.
    Slot* slot = find(next_sequence_);
    if (slot != nullptr && slot->capture_time != play_capture_) {
      playing_ = false;
      continue;
    }

    // Keep the real offset near the target: insert a concealment frame when playing too
    // early, drop one frame when too late (jitter fell, or the sender's clock is fast).
    const int64_t error = now - play_capture_ - target_offset_;
    if (error < -settings_.early_slack_samples) {
      ++stats_.inserted;
      return emit(PlayoutKind::kConceal, nullptr, -1, -1);
    }
    if (error > frame + settings_.hysteresis_samples) {
      Slot* after = find(next_sequence_ + 1);
      if (after == nullptr || after->capture_time == play_capture_ + frame) {
        if (slot != nullptr) slot->used = false;
        ++stats_.dropped;
        ++next_sequence_;
        play_capture_ += frame;
        slot = after;
      }
    }

    const int64_t sequence = next_sequence_;
    const int64_t capture = play_capture_;
    last_playout_offset_ = now - capture;
    if (slot != nullptr) {
      // The frame is here: decode it.
      ++next_sequence_;
      play_capture_ += frame;
      missing_run_ = 0;
      ++stats_.decoded;
      PlayoutDecision decision = emit(PlayoutKind::kDecode, slot, capture, sequence);
      slot->used = false;
      return decision;
    }
    // Missing: FEC from the next packet when it directly follows, else conceal. Concealment
    // goes on only while a newer packet continues this talkspurt within a few frames (same
    // spacing in sequence and time); otherwise (the sender paused, the last packet was lost,
    // or a forwarding server skipped a stretch) the talkspurt ends after max_conceal_frames
    // and the next one starts when due.
    Slot* after = find(next_sequence_ + 1);
    const Slot* newer = after;
    if (newer == nullptr) {
      for (const Slot& other : slots_) {
        if (other.used && other.sequence > sequence &&
            (newer == nullptr || other.sequence < newer->sequence)) {
          newer = &other;
        }
      }
    }
    const bool continues = newer != nullptr &&
                           newer->sequence - sequence <= settings_.max_conceal_frames &&
                           newer->capture_time - capture == (newer->sequence - sequence) * frame;
    if (continues) {
      missing_run_ = 0;
    } else if (++missing_run_ > settings_.max_conceal_frames) {
      playing_ = false;
      ++stats_.silence;
      return {};
    }
    ++next_sequence_;
    play_capture_ += frame;
    if (after != nullptr && after->capture_time == capture + frame) {
      ++stats_.fec;
      return emit(PlayoutKind::kFec, after, capture, sequence);
    }
    ++stats_.concealed;
    return emit(PlayoutKind::kConceal, nullptr, capture, sequence);
  }
  ++stats_.silence;
  return {};
}

}  // namespace vistel
