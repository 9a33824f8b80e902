// Byte reading/writing, CRC-32 and the embedded config lookup.
#include <gtest/gtest.h>

#include "common/base/bytes.hpp"
#include "common/base/embedded.hpp"

namespace vistel {
namespace {

TEST(Bytes, Crc32MatchesTheStandardCheckValue) {
  const std::string_view text = "123456789";
  EXPECT_EQ(crc32({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()}), 0xCBF43926u);
}

TEST(Bytes, WriteThenReadRoundTrips) {
  std::vector<std::uint8_t> buf;
  ByteWriter w(buf);
  w.u8(7);
  w.u16(0xBEEF);
  w.u32(123456789u);
  w.f32(-1.5f);
  w.f64(3.25);
  w.string("vistel");
  ByteReader r(buf);
  EXPECT_EQ(r.u8(), 7);
  EXPECT_EQ(r.u16(), 0xBEEF);
  EXPECT_EQ(r.u32(), 123456789u);
  EXPECT_EQ(r.f32(), -1.5f);
  EXPECT_EQ(r.f64(), 3.25);
  EXPECT_EQ(r.string(), "vistel");
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(r.remaining(), 0u);
  // Little-endian on the wire.
  EXPECT_EQ(buf[1], 0xEF);
  EXPECT_EQ(buf[2], 0xBE);
}

TEST(Bytes, ReadsPastTheEndFailAndLatch) {
  std::vector<std::uint8_t> buf = {1, 2, 3};
  ByteReader r(buf);
  EXPECT_EQ(r.u16(), 0x0201);
  EXPECT_EQ(r.u32(), 0u);
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.u8(), 0);  // latched: no more reads succeed
  EXPECT_FALSE(r.ok());

  // A length prefix larger than the input is refused without allocating it.
  std::vector<std::uint8_t> lying;
  ByteWriter(lying).u32(0xFFFFFFF0u);
  ByteReader r2(lying);
  EXPECT_TRUE(r2.string().empty());
  EXPECT_FALSE(r2.ok());
  std::vector<float> floats;
  ByteReader r3(buf);
  EXPECT_FALSE(r3.array(floats, 1u << 30));
  EXPECT_TRUE(floats.empty());
}

TEST(Bytes, EmptyArraysReadWithoutTouchingMemory) {
  std::vector<std::uint8_t> buf = {9};
  ByteReader r(buf);
  std::vector<float> none;
  EXPECT_TRUE(r.array(none, 0));  // data() of an empty vector is null: must not memcpy
  EXPECT_TRUE(none.empty());
  EXPECT_EQ(r.u8(), 9);
  EXPECT_TRUE(r.ok());
}

TEST(Embedded, UnknownConfigIsAClearError) {
  auto text = readConfigText("config/does/not/exist.toml");
  ASSERT_FALSE(text.ok());
  EXPECT_NE(text.error().message.find("config/does/not/exist.toml"), std::string::npos);
}

}  // namespace
}  // namespace vistel
