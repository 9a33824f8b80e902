// The shell's pure helpers (issue 20, findings 5 and 9): connections admitted at accept
// in total and per source address, and datagram drops counted by class with a log summary
// at most once per interval.
#include <string>

#include <gtest/gtest.h>

#include "server/shell/connection_limits.hpp"
#include "server/shell/datagram_drops.hpp"

namespace vistel::server {
namespace {

TEST(ConnectionLimits, RefusesPastThePerAddressAndTotalLimits) {
  ConnectionLimits limits(4, 2, false);
  EXPECT_EQ(limits.admit("127.0.0.4", false), "");
  EXPECT_EQ(limits.admit("127.0.0.4", false), "");
  EXPECT_EQ(limits.admit("127.0.0.4", false), "connections per address");
  EXPECT_EQ(limits.admit("127.0.0.5", false), "");
  EXPECT_EQ(limits.openFrom("127.0.0.4"), 2);
  // Loopback is exempt from the per-address limit, not from the total.
  EXPECT_EQ(limits.admit("127.0.0.1", true), "");
  EXPECT_EQ(limits.admit("127.0.0.1", true), "connection limit");
  EXPECT_EQ(limits.open(), 4);
  EXPECT_EQ(limits.refusals().at("connections per address"), 1u);
  EXPECT_EQ(limits.refusals().at("connection limit"), 1u);
  // A closed connection frees its slot; releasing an unknown address changes nothing.
  limits.release("127.0.0.4");
  limits.release("127.0.0.9");
  EXPECT_EQ(limits.open(), 3);
  EXPECT_EQ(limits.admit("127.0.0.4", false), "");
}

TEST(ConnectionLimits, ZeroMeansNoLimitAndLoopbackCanBeLimited) {
  ConnectionLimits none(0, 0, false);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(none.admit("127.0.0.4", false), "");
  ConnectionLimits strict(0, 1, true);
  EXPECT_EQ(strict.admit("127.0.0.1", true), "");
  EXPECT_EQ(strict.admit("127.0.0.1", true), "connections per address");
}

TEST(DatagramDrops, ReasonsFallIntoTheirClasses) {
  EXPECT_EQ(classifyDropReason("not a vistel datagram"), DropClass::kBadHeader);
  EXPECT_EQ(classifyDropReason("truncated datagram"), DropClass::kBadHeader);
  EXPECT_EQ(classifyDropReason("datagram for unknown member"), DropClass::kUnknownKey);
  EXPECT_EQ(classifyDropReason("bad key"), DropClass::kUnknownKey);
  EXPECT_EQ(classifyDropReason("wrong endpoint"), DropClass::kUnverifiedAddress);
  EXPECT_EQ(classifyDropReason("endpoint not bound"), DropClass::kUnverifiedAddress);
  EXPECT_EQ(classifyDropReason("posture rate exceeded"), DropClass::kRate);
  EXPECT_EQ(classifyDropReason("malformed posture"), DropClass::kBadPayload);
  EXPECT_EQ(classifyDropReason("something new"), DropClass::kOther);
  EXPECT_EQ(classifyDropReason("bad datagram tag"), DropClass::kUnknownKey);
  EXPECT_EQ(classifyDropReason("replayed datagram"), DropClass::kReplay);
  EXPECT_EQ(classifyDropReason("datagram too old"), DropClass::kReplay);
  EXPECT_EQ(classifyDropReason("capture time too old"), DropClass::kBadPayload);
  EXPECT_EQ(dropClassName(DropClass::kReplay), "replay");
}

TEST(DatagramDrops, CountsByClassAndSummarisesOncePerInterval) {
  DatagramDrops drops(10.0);
  // The first drop is reported at once; the next ones wait for the interval.
  ASSERT_TRUE(drops.add("not a vistel datagram", 0.0).has_value());
  for (int i = 0; i < 1000; ++i) {
    EXPECT_FALSE(drops.add("datagram for unknown member", 0.001 * i).has_value());
  }
  EXPECT_FALSE(drops.add("wrong endpoint", 9.9).has_value());
  const auto line = drops.add("bad key", 10.5);
  ASSERT_TRUE(line.has_value());
  EXPECT_NE(line->find("1002 datagram(s) in the last 10 s"), std::string::npos) << *line;
  EXPECT_NE(line->find("1001 unknown key"), std::string::npos) << *line;
  EXPECT_NE(line->find("1 unverified address"), std::string::npos) << *line;

  EXPECT_EQ(drops.count(DropClass::kBadHeader), 1u);
  EXPECT_EQ(drops.count(DropClass::kUnknownKey), 1001u);
  EXPECT_EQ(drops.count(DropClass::kUnverifiedAddress), 1u);
  EXPECT_EQ(drops.total(), 1003u);
  const auto by_reason = drops.byReason();
  EXPECT_EQ(by_reason.size(), static_cast<std::size_t>(kDropClassCount));
  EXPECT_EQ(by_reason.at("unknown key"), 1001u);
  EXPECT_EQ(by_reason.at("rate"), 0u);
}

}  // namespace
}  // namespace vistel::server
