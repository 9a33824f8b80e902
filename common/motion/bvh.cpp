// BVH parsing (Biovision hierarchy files): a strict reader that never trusts its input.
//
// Grammar accepted:
//   HIERARCHY
//   ROOT name { OFFSET x y z [CHANNELS n c1..cn] (JOINT name {...} | End Site { OFFSET x y z })* }
//   MOTION
//   Frames: N
//   Frame Time: dt
//   N lines of exactly (sum of n) numbers
// Tokens are separated by any whitespace (tabs, spaces, CRLF or LF); braces are tokens of
// their own. OFFSET and CHANNELS come before a joint's children, once each.
#include "common/motion/bvh.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <unordered_set>

#include "common/base/file.hpp"

namespace vistel {
namespace {

constexpr double kMaxFrameTime = 60.0;  // seconds; anything longer is not a motion clip

bool isSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

// A token as it may be shown in a message: at most 40 characters, non-printable bytes
// escaped (the text may be hostile).
std::string shown(std::string_view token) {
  std::string out;
  for (std::size_t i = 0; i < token.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(token[i]);
    if (c >= 0x20 && c < 0x7f) {
      out.push_back(static_cast<char>(c));
    } else {
      out += fmt::format("\\x{:02x}", c);
    }
  }
  if (token.size() > 40) out += "...";
  return out;
}

enum class NumberStatus { kOk, kNotNumber, kNonFinite };

// The whole token as a finite float (a leading '+' is allowed).
NumberStatus parseFloat(std::string_view token, float& out) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return NumberStatus::kNotNumber;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, out);
  if (ec == std::errc::result_out_of_range && ptr == end) return NumberStatus::kNonFinite;
  if (ec != std::errc() || ptr != end) return NumberStatus::kNotNumber;
  return std::isfinite(out) ? NumberStatus::kOk : NumberStatus::kNonFinite;
}

bool parseDouble(std::string_view token, double& out) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, out);
  return ec == std::errc() && ptr == end && !token.empty() && std::isfinite(out);
}

bool parseInt(std::string_view token, long long& out) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, out);
  return ec == std::errc() && ptr == end && !token.empty();
}

bool equalsNoCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const auto lower = [](char c) { return c >= 'A' && c <= 'Z' ? static_cast<char>(c + 32) : c; };
    if (lower(a[i]) != lower(b[i])) return false;
  }
  return true;
}

std::optional<BvhChannel> channelFromName(std::string_view name) {
  static constexpr std::pair<std::string_view, BvhChannel> kNames[] = {
      {"Xposition", BvhChannel::kXposition}, {"Yposition", BvhChannel::kYposition},
      {"Zposition", BvhChannel::kZposition}, {"Xrotation", BvhChannel::kXrotation},
      {"Yrotation", BvhChannel::kYrotation}, {"Zrotation", BvhChannel::kZrotation}};
  for (const auto& [text, channel] : kNames) {
    if (equalsNoCase(name, text)) return channel;
  }
  return std::nullopt;
}

// Splits the text into whitespace-separated tokens, braces apart, counting lines.
class Lexer {
 public:
  struct Token {
    std::string_view text;  // empty at the end of the text
    int line = 1;
  };

  explicit Lexer(std::string_view text) : text_(text) {}

  Token next() {
    while (pos_ < text_.size() && isSpace(text_[pos_])) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
    Token token{{}, line_};
    if (pos_ >= text_.size()) return token;
    const std::size_t start = pos_;
    if (text_[pos_] == '{' || text_[pos_] == '}') {
      ++pos_;
    } else {
      while (pos_ < text_.size() && !isSpace(text_[pos_]) && text_[pos_] != '{' &&
             text_[pos_] != '}') {
        ++pos_;
      }
    }
    token.text = text_.substr(start, pos_ - start);
    return token;
  }

  std::size_t position() const { return pos_; }
  int line() const { return line_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  int line_ = 1;
};

class Parser {
 public:
  Parser(std::string_view text, std::string_view source) : text_(text), lexer_(text) {
    clip_.source = std::string(source);
  }

  Result<MotionClip> run() {
    if (Status s = parseHierarchy(); !s) return s.error();
    if (Status s = parseMotion(); !s) return s.error();
    return std::move(clip_);
  }

 private:
  // Per open joint block while reading the hierarchy.
  struct Open {
    int joint = 0;
    bool has_offset = false;
    bool has_channels = false;
    bool has_children = false;
  };

  template <typename... Args>
  Error error(int line, fmt::format_string<Args...> format, Args&&... args) const {
    return fail("{}:{}: {}", clip_.source, line, fmt::format(format, std::forward<Args>(args)...));
  }

  static std::string describe(const Lexer::Token& token) {
    if (token.text.empty()) return "end of file";
    return fmt::format("'{}'", shown(token.text));
  }

  Status expect(std::string_view word, std::string_view context) {
    const Lexer::Token token = lexer_.next();
    if (token.text != word) {
      return error(token.line, "expected '{}' {}, found {}", word, context, describe(token));
    }
    return {};
  }

  Status readVector(std::string_view what, glm::vec3& out) {
    for (int i = 0; i < 3; ++i) {
      const Lexer::Token token = lexer_.next();
      if (token.text.empty()) {
        return error(token.line, "unexpected end of file in {} (3 numbers expected)", what);
      }
      switch (parseFloat(token.text, out[i])) {
        case NumberStatus::kOk:
          break;
        case NumberStatus::kNonFinite:
          return error(token.line, "non-finite number '{}' in {}", shown(token.text), what);
        case NumberStatus::kNotNumber:
          return error(token.line, "expected a number in {} (3 numbers), found '{}'", what,
                       shown(token.text));
      }
    }
    return {};
  }

  Status newJoint(const Lexer::Token& keyword, int parent) {
    const Lexer::Token name = lexer_.next();
    if (name.text.empty() || name.text == "{" || name.text == "}") {
      return error(name.line, "expected a joint name after '{}', found {}", keyword.text,
                   describe(name));
    }
    if (name.text.size() > kBvhMaxNameLength) {
      return error(name.line, "joint name '{}' is longer than {} characters", shown(name.text),
                   kBvhMaxNameLength);
    }
    if (static_cast<int>(clip_.joints.size()) >= kBvhMaxJoints) {
      return error(name.line, "more than {} joints", kBvhMaxJoints);
    }
    if (!names_.insert(std::string(name.text)).second) {
      return error(name.line, "joint name '{}' appears twice", shown(name.text));
    }
    BvhJoint joint;
    joint.name = std::string(name.text);
    joint.parent = parent;
    joint.first_channel = clip_.channel_count;  // (a joint without CHANNELS has none)
    clip_.joints.push_back(std::move(joint));
    return expect("{", fmt::format("after joint name '{}'", shown(name.text)));
  }

  Status readChannels(const Lexer::Token& keyword, BvhJoint& joint) {
    const Lexer::Token count_token = lexer_.next();
    long long count = 0;
    if (!parseInt(count_token.text, count)) {
      return error(count_token.line, "expected a channel count after CHANNELS, found {}",
                   describe(count_token));
    }
    if (count != 0 && count != 3 && count != 6) {
      return error(count_token.line, "joint '{}' has {} channels (0, 3 or 6 expected)", joint.name,
                   count);
    }
    int positions = 0;
    int rotations = 0;
    unsigned seen = 0;
    for (long long i = 0; i < count; ++i) {
      const Lexer::Token token = lexer_.next();
      const std::optional<BvhChannel> channel = channelFromName(token.text);
      if (!channel) {
        return error(token.line, "joint '{}': expected a channel name ({} of {}), found {}",
                     joint.name, i + 1, count, describe(token));
      }
      const unsigned bit = 1u << static_cast<unsigned>(*channel);
      if ((seen & bit) != 0) {
        return error(token.line, "joint '{}' lists channel '{}' twice", joint.name,
                     shown(token.text));
      }
      seen |= bit;
      if (*channel <= BvhChannel::kZposition) {
        ++positions;
      } else {
        ++rotations;
      }
      joint.channels.push_back(*channel);
    }
    if ((positions != 0 && positions != 3) || (rotations != 0 && rotations != 3)) {
      return error(keyword.line,
                   "joint '{}' has {} position and {} rotation channels (all three or none "
                   "of each expected)",
                   joint.name, positions, rotations);
    }
    joint.first_channel = clip_.channel_count;
    clip_.channel_count += static_cast<int>(count);
    return {};
  }

  Status parseHierarchy() {
    const Lexer::Token first = lexer_.next();
    if (first.text.empty()) return error(first.line, "empty file (expected 'HIERARCHY')");
    if (first.text != "HIERARCHY") {
      return error(first.line, "expected 'HIERARCHY', found {}", describe(first));
    }
    const Lexer::Token root = lexer_.next();
    if (root.text != "ROOT") return error(root.line, "expected 'ROOT', found {}", describe(root));
    if (Status s = newJoint(root, kNoParent); !s) return s;
    std::vector<Open> open{{0, false, false, false}};

    while (!open.empty()) {
      const Lexer::Token token = lexer_.next();
      Open& top = open.back();
      BvhJoint& joint = clip_.joints[static_cast<std::size_t>(top.joint)];
      if (token.text.empty()) {
        return error(token.line, "unexpected end of file inside joint '{}' (missing '}}')",
                     joint.name);
      }
      if (token.text == "OFFSET") {
        if (top.has_children) {
          return error(token.line, "OFFSET of joint '{}' after its children", joint.name);
        }
        if (top.has_offset) return error(token.line, "joint '{}' has two OFFSETs", joint.name);
        if (Status s = readVector(fmt::format("OFFSET of '{}'", joint.name), joint.offset); !s) {
          return s;
        }
        top.has_offset = true;
      } else if (token.text == "CHANNELS") {
        if (top.has_children) {
          return error(token.line, "CHANNELS of joint '{}' after its children", joint.name);
        }
        if (top.has_channels) return error(token.line, "joint '{}' has two CHANNELS", joint.name);
        if (Status s = readChannels(token, joint); !s) return s;
        top.has_channels = true;
      } else if (token.text == "JOINT") {
        if (!top.has_offset) {
          return error(token.line, "joint '{}' has a child before its OFFSET", joint.name);
        }
        top.has_children = true;
        const int parent = top.joint;
        if (Status s = newJoint(token, parent); !s) return s;
        // `top` and `joint` may dangle after the push_backs below and above.
        open.push_back({static_cast<int>(clip_.joints.size()) - 1, false, false, false});
      } else if (token.text == "End") {
        if (Status s = expect("Site", "after 'End'"); !s) return s;
        if (!top.has_offset) {
          return error(token.line, "joint '{}' has an End Site before its OFFSET", joint.name);
        }
        if (joint.end_site) return error(token.line, "joint '{}' has two End Sites", joint.name);
        if (Status s = expect("{", "after 'End Site'"); !s) return s;
        if (Status s = expect("OFFSET", "in End Site"); !s) return s;
        glm::vec3 offset;
        if (Status s = readVector(fmt::format("End Site of '{}'", joint.name), offset); !s) {
          return s;
        }
        if (Status s = expect("}", "closing End Site"); !s) return s;
        joint.end_site = offset;
        top.has_children = true;
      } else if (token.text == "}") {
        if (!top.has_offset) return error(token.line, "joint '{}' has no OFFSET", joint.name);
        open.pop_back();
      } else if (token.text == "MOTION" || token.text == "ROOT" || token.text == "HIERARCHY") {
        return error(token.line, "unexpected '{}' inside joint '{}' (missing '}}')", token.text,
                     joint.name);
      } else {
        return error(token.line, "unexpected token '{}' in joint '{}'", shown(token.text),
                     joint.name);
      }
    }

    const Lexer::Token motion = lexer_.next();
    if (motion.text == "ROOT") {
      return error(motion.line, "a second ROOT (only one skeleton per file is supported)");
    }
    if (motion.text != "MOTION") {
      return error(motion.line, "expected 'MOTION' after the hierarchy, found {}",
                   describe(motion));
    }
    if (clip_.channel_count == 0) return error(motion.line, "the hierarchy has no channels");
    return {};
  }

  // "Key:" followed by a value token, or "Key:value" as one token.
  Status readKeyValue(std::string_view key, Lexer::Token& value) {
    const Lexer::Token token = lexer_.next();
    if (token.text == key) {
      value = lexer_.next();
      if (value.text.empty()) return error(value.line, "missing value after '{}'", key);
      return {};
    }
    if (token.text.size() > key.size() && token.text.starts_with(key)) {
      value = {token.text.substr(key.size()), token.line};
      return {};
    }
    return error(token.line, "expected '{}', found {}", key, describe(token));
  }

  Status parseMotion() {
    Lexer::Token frames_token;
    if (Status s = readKeyValue("Frames:", frames_token); !s) return s;
    long long frames = 0;
    if (!parseInt(frames_token.text, frames)) {
      return error(frames_token.line, "frame count '{}' is not an integer",
                   shown(frames_token.text));
    }
    if (frames < 1 || frames > kBvhMaxFrames) {
      return error(frames_token.line, "frame count {} out of range (1..{})", frames, kBvhMaxFrames);
    }
    const Lexer::Token frame_word = lexer_.next();
    if (frame_word.text != "Frame") {
      return error(frame_word.line, "expected 'Frame Time:', found {}", describe(frame_word));
    }
    Lexer::Token time_token;
    if (Status s = readKeyValue("Time:", time_token); !s) return s;
    double frame_time = 0.0;
    if (!parseDouble(time_token.text, frame_time) || frame_time <= 0.0 ||
        frame_time > kMaxFrameTime) {
      return error(time_token.line, "frame time '{}' is not a number in (0, {}] seconds",
                   shown(time_token.text), kMaxFrameTime);
    }
    clip_.frame_count = static_cast<int>(frames);
    clip_.frame_time = frame_time;

    // The rest of the "Frame Time" line must be empty.
    std::size_t pos = lexer_.position();
    int line = lexer_.line();
    while (pos < text_.size() && text_[pos] != '\n') {
      if (!isSpace(text_[pos])) {
        return error(line, "unexpected text after the frame time: '{}'",
                     shown(text_.substr(pos, 20)));
      }
      ++pos;
    }

    // Every value takes at least two bytes (a digit and a separator), so the count is
    // checked against what is left before anything is reserved.
    const auto channels = static_cast<std::uint64_t>(clip_.channel_count);
    const std::uint64_t needed = static_cast<std::uint64_t>(frames) * channels * 2 - 1;
    const std::uint64_t remaining = text_.size() - pos;
    if (needed > remaining) {
      return error(frames_token.line,
                   "{} frames of {} values need at least {} bytes, but only {} remain "
                   "(frame count mismatch or truncated file)",
                   frames, channels, needed, remaining);
    }
    clip_.values.reserve(static_cast<std::size_t>(frames) * channels);

    int read = 0;
    while (pos < text_.size()) {
      // One line: [pos, eol).
      if (text_[pos] == '\n') {
        ++pos;
        ++line;
      }
      if (pos >= text_.size()) break;
      std::size_t eol = text_.find('\n', pos);
      if (eol == std::string_view::npos) eol = text_.size();
      const std::string_view row = text_.substr(pos, eol - pos);
      pos = eol;
      std::size_t count = 0;
      std::size_t i = 0;
      while (i < row.size()) {
        while (i < row.size() && isSpace(row[i])) ++i;
        if (i >= row.size()) break;
        std::size_t j = i;
        while (j < row.size() && !isSpace(row[j])) ++j;
        const std::string_view token = row.substr(i, j - i);
        i = j;
        if (count == 0 && read == clip_.frame_count) {
          return error(line, "more frame lines than 'Frames: {}'", clip_.frame_count);
        }
        if (count == channels) {
          return error(line, "frame {} has more than {} values", read, channels);
        }
        float value = 0.0f;
        switch (parseFloat(token, value)) {
          case NumberStatus::kOk:
            break;
          case NumberStatus::kNonFinite:
            return error(line, "frame {}: non-finite value '{}'", read, shown(token));
          case NumberStatus::kNotNumber:
            return error(line, "frame {}: '{}' is not a number", read, shown(token));
        }
        clip_.values.push_back(value);
        ++count;
      }
      if (count == 0) continue;  // blank line
      if (count != channels) {
        return error(line, "frame {} has {} values, expected {}", read, count, channels);
      }
      ++read;
    }
    if (read != clip_.frame_count) {
      return error(line, "the file ends after {} of {} frames (frame count mismatch)", read,
                   clip_.frame_count);
    }
    return {};
  }

  std::string_view text_;
  Lexer lexer_;
  MotionClip clip_;
  std::unordered_set<std::string> names_;
};

}  // namespace

Result<MotionClip> parseBvh(std::string_view text, std::string_view source_name, BvhUnits units) {
  Result<MotionClip> clip = Parser(text, source_name).run();
  if (clip) clip->unit_scale = bvhUnitScale(*clip, units);
  return clip;
}

Result<MotionClip> loadBvh(const std::string& path, BvhUnits units) {
  Result<std::string> text = readFileText(path, std::size_t{512} << 20);
  if (!text) return text.error();
  return parseBvh(*text, path, units);
}

float bvhUnitScale(const MotionClip& clip, BvhUnits units) {
  switch (units) {
    case BvhUnits::kMetres:
      return 1.0f;
    case BvhUnits::kCentimetres:
      return 0.01f;
    case BvhUnits::kInches:
      return 0.0254f;
    case BvhUnits::kCmu:
      return kCmuUnitMetres;
    case BvhUnits::kAuto:
      break;
  }
  // Largest extent of the zero pose (joints and end sites).
  if (clip.joints.empty()) return 1.0f;
  std::vector<glm::vec3> positions(clip.joints.size());
  glm::vec3 lo(std::numeric_limits<float>::max());
  glm::vec3 hi(std::numeric_limits<float>::lowest());
  for (std::size_t j = 0; j < clip.joints.size(); ++j) {
    const BvhJoint& joint = clip.joints[j];
    positions[j] = joint.offset;
    if (joint.parent != kNoParent)
      positions[j] += positions[static_cast<std::size_t>(joint.parent)];
    lo = glm::min(lo, positions[j]);
    hi = glm::max(hi, positions[j]);
    if (joint.end_site) {
      lo = glm::min(lo, positions[j] + *joint.end_site);
      hi = glm::max(hi, positions[j] + *joint.end_site);
    }
  }
  const glm::vec3 size = hi - lo;
  const float extent = std::max({size.x, size.y, size.z});
  if (extent < 5.0f) return 1.0f;
  if (extent < 60.0f) return kCmuUnitMetres;
  return 0.01f;
}

}  // namespace vistel
