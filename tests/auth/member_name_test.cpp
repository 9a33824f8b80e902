// Member names (common/auth/member_name.hpp): a table of names taken and refused, with the
// position the refusal names.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/auth/member_name.hpp"

namespace vistel::auth {
namespace {

TEST(MemberName, TakesPrintableAsciiAndUnicodeLetters) {
  for (const std::string& name :
       std::vector<std::string>{"a", "alice", "bob-2", "Dr. Who (guest)", "x y", "~!@#$%^&*",
                                std::string(64, 'm'), "Zoë", "Łukasz", "李小龙", "Ελένη", "محمد",
                                "שלום", "🙂 smile", "e\xCC\x81",  // e + combining acute
                                std::string(16, 'a') + "\xF0\x9F\x99\x82"}) {
    const Status st = validateMemberName(name);
    EXPECT_TRUE(st.ok()) << name << ": " << (st.ok() ? "" : st.error().message);
  }
  // 64 characters of 4 bytes each: 256 bytes, still 64 characters.
  std::string wide;
  for (int i = 0; i < 64; ++i) wide += "\xF0\x9F\x99\x82";
  EXPECT_TRUE(validateMemberName(wide).ok());
}

struct Refused {
  std::string name;
  std::string says;  // part of the message
};

TEST(MemberName, RefusesWithTheOffendingPosition) {
  const std::vector<Refused> table = {
      {"", "empty"},
      {std::string(65, 'm'), "longer than 64 characters"},
      {"a\tb", "character 2 (U+0009) is a control character"},
      {"ab\ncd", "character 3 (U+000A) is a control character"},
      {std::string("a\0b", 3), "character 2 (U+0000) is a control character"},
      {"del\x7F", "character 4 (U+007F) is a control character"},
      {"c1\xC2\x85", "character 3 (U+0085) is a control character"},
      {"c1\xC2\x9F", "character 3 (U+009F) is a control character"},
      {"evil\xE2\x80\xAEtxt.exe", "character 5 (U+202E) is a bidirectional control"},
      {"\xE2\x80\x8Eleft", "character 1 (U+200E) is a bidirectional control"},
      {"x\xE2\x80\x8F", "character 2 (U+200F) is a bidirectional control"},
      {"x\xE2\x80\xAA", "character 2 (U+202A) is a bidirectional control"},
      {"x\xE2\x81\xA6", "character 2 (U+2066) is a bidirectional control"},
      {"x\xE2\x81\xA9", "character 2 (U+2069) is a bidirectional control"},
      {"x\xD8\x9C", "character 2 (U+061C) is a bidirectional control"},
      {"zero\xE2\x80\x8Bwidth", "character 5 (U+200B) is an invisible format character"},
      {"j\xE2\x80\x8Dj", "character 2 (U+200D) is an invisible format character"},
      {"w\xE2\x81\xA0j", "character 2 (U+2060) is an invisible format character"},
      {"\xEF\xBB\xBF"
       "bom",
       "character 1 (U+FEFF) is an invisible format character"},
      {"a\xE2\x80\xA8"
       "b",
       "character 2 (U+2028) is a line or paragraph separator"},
      {" alice", "character 1 (U+0020) is whitespace at the start"},
      {"alice ", "character 6 (U+0020) is whitespace at the end"},
      {"\xC2\xA0nbsp", "character 1 (U+00A0) is whitespace at the start"},
      {"Zoë\xE3\x80\x80", "character 4 (U+3000) is whitespace at the end"},
      {" ", "whitespace at the start"},
      {"ab\xFF", "byte 3 is not valid UTF-8"},
      {"ab\x80", "byte 3 is not valid UTF-8"},
      {"\xC0\xAF", "byte 1 is not valid UTF-8"},            // overlong '/'
      {"a\xE0\x80\xAF", "byte 2 is not valid UTF-8"},       // overlong, 3 bytes
      {"a\xED\xA0\x80", "byte 2 is not valid UTF-8"},       // a surrogate
      {"ab\xF4\x90\x80\x80", "byte 3 is not valid UTF-8"},  // past U+10FFFF
      {"abc\xE2\x80", "byte 4 is not valid UTF-8"},         // truncated
      {"a\xE2"
       "bc",
       "byte 2 is not valid UTF-8"},  // missing continuation
  };
  for (const Refused& r : table) {
    const Status st = validateMemberName(r.name);
    ASSERT_FALSE(st.ok()) << "taken: " << r.name;
    EXPECT_NE(st.error().message.find(r.says), std::string::npos)
        << "name '" << r.name << "': " << st.error().message << " (expected: " << r.says << ")";
  }
}

TEST(MemberName, EveryNameTheOldRuleTookStillPassesUnlessItHasOuterSpaces) {
  // The old rule: 1..64 bytes >= 0x20 other than 0x7F; ASCII is what clients sent.
  for (int c = 0x21; c < 0x7F; ++c) {
    const std::string name(1, static_cast<char>(c));
    EXPECT_TRUE(validateMemberName(name).ok()) << c;
    EXPECT_TRUE(validateMemberName("a" + name + " " + name).ok()) << c;
  }
}

}  // namespace
}  // namespace vistel::auth
