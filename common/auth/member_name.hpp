// What a member name may be (Join.name; the lobby refuses others with BAD_JOIN).
//
// A name is 1..kMaxNameChars Unicode characters (code points) of valid UTF-8 (no overlong
// forms, surrogates or values past U+10FFFF) and holds none of:
// - control characters: C0 (U+0000-U+001F), DEL (U+007F), C1 (U+0080-U+009F);
// - bidirectional controls, which reorder what is drawn after them: U+061C, U+200E,
//   U+200F, U+202A-U+202E, U+2066-U+2069;
// - invisible format characters: U+200B-U+200D, U+2060-U+2064, U+FEFF, and the line and
//   paragraph separators U+2028, U+2029;
// and it neither starts nor ends with whitespace (U+0020, U+00A0, U+1680, U+2000-U+200A,
// U+202F, U+205F, U+3000). Every name the lobby took before (1..64 bytes of printable
// ASCII) still passes, unless it starts or ends with a space.
//
// The error says what is wrong and where: "character 3 (U+202E) is a bidirectional
// control", "byte 5 is not valid UTF-8". Positions count from 1. Cost: one pass.
#pragma once

#include <string_view>

#include "common/base/result.hpp"

namespace vistel::auth {

inline constexpr int kMaxNameChars = 64;

Status validateMemberName(std::string_view name);

}  // namespace vistel::auth
