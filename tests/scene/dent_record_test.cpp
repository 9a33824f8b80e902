// Dent records (common/scene/dent_record.hpp): a body's elastic memory, sparse and quantised
// to 0.1 mm, survives the round trip within half a quantum, and malformed records are
// refused with the entry named.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "common/scene/dent_record.hpp"

namespace vistel {
namespace {

TEST(DentRecord, RoundTripsWithinHalfAQuantum) {
  std::vector<float> memory(1000, 0.0f);
  memory[0] = -0.0123f;
  memory[1] = -0.00004f;  // rounds to no dent
  memory[2] = -0.00006f;  // rounds to one quantum
  memory[517] = -0.0331f;
  memory[999] = -3.0f;   // deeper than a dent can be: clamped to 1 m
  memory[400] = 0.002f;  // a bulge: memory never holds one; left out
  memory[401] = NAN;     // nor this
  DentRecord r;
  recordDents(memory, r);
  EXPECT_EQ(r.vertex_count, 1000u);
  EXPECT_EQ(r.gaps, (std::vector<std::uint32_t>{0, 1, 514, 481}));
  EXPECT_EQ(r.depths, (std::vector<std::uint32_t>{123, 1, 331, kMaxDentQuanta}));
  EXPECT_EQ(dentCount(r), 4u);

  std::vector<float> back(1000, -1.0f);  // every entry is overwritten
  ASSERT_TRUE(applyDents(r, back).ok());
  for (std::size_t v = 0; v < memory.size(); ++v) {
    const float want = v == 999                   ? -1.0f
                       : std::isfinite(memory[v]) ? std::min(memory[v], 0.0f)
                                                  : 0.0f;
    EXPECT_NEAR(back[v], want, 0.5f * kDentQuantumM + 1e-7f) << v;
  }
  // Recording what was applied gives the same record.
  DentRecord again;
  recordDents(back, again);
  EXPECT_EQ(again, r);
}

TEST(DentRecord, NoDentsIsAnEmptyRecord) {
  std::vector<float> memory(50, 0.0f);
  DentRecord r;
  r.gaps = {1, 2};
  r.depths = {3, 4};
  recordDents(memory, r);
  EXPECT_EQ(r.vertex_count, 50u);
  EXPECT_TRUE(r.gaps.empty());
  EXPECT_TRUE(r.depths.empty());
  std::vector<float> back(50, -0.01f);
  ASSERT_TRUE(applyDents(r, back).ok());
  for (float m : back) EXPECT_EQ(m, 0.0f);
}

TEST(DentRecord, MalformedRecordsAreRefusedAndChangeNothing) {
  const std::vector<std::uint32_t> gaps = {3, 0, 5};
  const std::vector<std::uint32_t> depths = {10, 20, 30};
  EXPECT_TRUE(checkDents(11, gaps, depths, 3).ok());  // vertices 3, 4, 10
  const auto error = [](const Status& st) { return st ? std::string() : st.error().message; };
  EXPECT_NE(error(checkDents(10, gaps, depths, 3)).find("entry 2 names vertex 10 of a skin of 10"),
            std::string::npos);
  EXPECT_NE(error(checkDents(11, gaps, depths, 2)).find("more than the limit of 2"),
            std::string::npos);
  EXPECT_NE(error(checkDents(11, gaps, std::vector<std::uint32_t>{10, 20}, 3))
                .find("3 vertex gaps but 2"),
            std::string::npos);
  EXPECT_NE(error(checkDents(11, gaps, std::vector<std::uint32_t>{10, 0, 30}, 3))
                .find("entry 1 (vertex 4) has depth 0"),
            std::string::npos);
  EXPECT_FALSE(checkDents(11, gaps, std::vector<std::uint32_t>{10, kMaxDentQuanta + 1, 30}, 3));
  // A gap that would wrap past 2^32 is still outside the skin.
  EXPECT_FALSE(checkDents(4'000'000'000u, std::vector<std::uint32_t>{3'999'999'999u, 0xFFFFFFFFu},
                          std::vector<std::uint32_t>{1, 1}, 2));

  DentRecord r;
  r.vertex_count = 11;
  r.gaps = gaps;
  r.depths = depths;
  std::vector<float> memory(12, -0.5f);
  const Status other_mesh = applyDents(r, memory);
  ASSERT_FALSE(other_mesh);
  EXPECT_NE(other_mesh.error().message.find("a record for 11 vertices, the body has 12"),
            std::string::npos);
  for (float m : memory) EXPECT_EQ(m, -0.5f);
  memory.resize(11);
  r.depths[2] = 0;
  EXPECT_FALSE(applyDents(r, memory));
  for (float m : memory) EXPECT_EQ(m, -0.5f);
}

}  // namespace
}  // namespace vistel
