#include "common/auth/member_name.hpp"

#include <cstdint>

namespace vistel::auth {
namespace {

// Decodes one UTF-8 sequence at text[at]; returns its length (0: invalid) and sets cp.
std::size_t decodeUtf8(std::string_view text, std::size_t at, char32_t& cp) {
  const auto byte = [&](std::size_t i) { return static_cast<std::uint8_t>(text[at + i]); };
  const std::uint8_t b0 = byte(0);
  std::size_t length = 0;
  char32_t min = 0;
  if (b0 < 0x80) {
    cp = b0;
    return 1;
  } else if ((b0 & 0xE0) == 0xC0) {
    length = 2;
    cp = b0 & 0x1F;
    min = 0x80;
  } else if ((b0 & 0xF0) == 0xE0) {
    length = 3;
    cp = b0 & 0x0F;
    min = 0x800;
  } else if ((b0 & 0xF8) == 0xF0) {
    length = 4;
    cp = b0 & 0x07;
    min = 0x10000;
  } else {
    return 0;  // a continuation byte or 0xF8..0xFF
  }
  if (text.size() - at < length) return 0;
  for (std::size_t i = 1; i < length; ++i) {
    if ((byte(i) & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (byte(i) & 0x3F);
  }
  // Overlong forms, surrogates, past the last code point.
  if (cp < min || (cp >= 0xD800 && cp <= 0xDFFF) || cp > 0x10FFFF) return 0;
  return length;
}

bool isWhitespace(char32_t c) {
  return c == 0x20 || c == 0xA0 || c == 0x1680 || (c >= 0x2000 && c <= 0x200A) || c == 0x202F ||
         c == 0x205F || c == 0x3000;
}

// Why a character may not appear in a name at all (nullptr: it may).
const char* forbidden(char32_t c) {
  if (c < 0x20 || c == 0x7F || (c >= 0x80 && c <= 0x9F)) return "a control character";
  if (c == 0x061C || c == 0x200E || c == 0x200F || (c >= 0x202A && c <= 0x202E) ||
      (c >= 0x2066 && c <= 0x2069)) {
    return "a bidirectional control";
  }
  if ((c >= 0x200B && c <= 0x200D) || (c >= 0x2060 && c <= 0x2064) || c == 0xFEFF) {
    return "an invisible format character";
  }
  if (c == 0x2028 || c == 0x2029) return "a line or paragraph separator";
  return nullptr;
}

}  // namespace

Status validateMemberName(std::string_view name) {
  if (name.empty()) return fail("member name is empty");
  int chars = 0;
  char32_t last = 0;
  for (std::size_t at = 0; at < name.size();) {
    // One character: valid UTF-8, allowed, not leading whitespace.
    char32_t cp = 0;
    const std::size_t length = decodeUtf8(name, at, cp);
    if (length == 0) return fail("member name: byte {} is not valid UTF-8", at + 1);
    ++chars;
    if (const char* why = forbidden(cp)) {
      return fail("member name: character {} (U+{:04X}) is {}", chars,
                  static_cast<std::uint32_t>(cp), why);
    }
    if (chars == 1 && isWhitespace(cp)) {
      return fail("member name: character 1 (U+{:04X}) is whitespace at the start",
                  static_cast<std::uint32_t>(cp));
    }
    if (chars > kMaxNameChars) {
      return fail("member name: longer than {} characters", kMaxNameChars);
    }
    last = cp;
    at += length;
  }
  if (isWhitespace(last)) {
    return fail("member name: character {} (U+{:04X}) is whitespace at the end", chars,
                static_cast<std::uint32_t>(last));
  }
  return {};
}

}  // namespace vistel::auth
