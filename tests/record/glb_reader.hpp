// Test helper: the JSON and BIN chunks of a .glb, and an accessor's floats (tightly packed
// float accessors only, as client/record writes them). Fails the test on a malformed file.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace vistel::test {

struct GlbFile {
  nlohmann::json json;
  std::vector<std::uint8_t> bin;
  bool ok = false;

  // The floats of accessor `index` (componentType FLOAT).
  std::vector<float> floats(int index) const {
    const nlohmann::json& acc = json["accessors"][static_cast<std::size_t>(index)];
    const nlohmann::json& view = json["bufferViews"][acc["bufferView"].get<std::size_t>()];
    const std::size_t per = acc["type"] == "SCALAR" ? 1
                            : acc["type"] == "VEC3" ? 3
                            : acc["type"] == "VEC4" ? 4
                                                    : 16;
    std::vector<float> out(acc["count"].get<std::size_t>() * per);
    const std::size_t offset = view["byteOffset"].get<std::size_t>();
    EXPECT_EQ(acc["componentType"].get<int>(), 5126);
    EXPECT_LE(offset + out.size() * 4, bin.size());
    if (acc["componentType"].get<int>() == 5126 && offset + out.size() * 4 <= bin.size())
      std::memcpy(out.data(), bin.data() + offset, out.size() * 4);
    return out;
  }
  // The index of the node with this name, or -1.
  int node(const std::string& name) const {
    for (std::size_t i = 0; i < json["nodes"].size(); ++i) {
      if (json["nodes"][i].value("name", "") == name) return static_cast<int>(i);
    }
    return -1;
  }
};

inline std::uint32_t glbWord(const std::vector<std::uint8_t>& b, std::size_t at) {
  std::uint32_t w = 0;
  std::memcpy(&w, b.data() + at, 4);
  return w;
}

inline GlbFile readGlb(const std::vector<std::uint8_t>& b) {
  GlbFile f;
  EXPECT_GE(b.size(), 20u);
  if (b.size() < 20) return f;
  EXPECT_EQ(glbWord(b, 0), 0x46546C67u);
  EXPECT_EQ(glbWord(b, 4), 2u);
  EXPECT_EQ(glbWord(b, 8), b.size());
  const std::uint32_t json_len = glbWord(b, 12);
  EXPECT_EQ(glbWord(b, 16), 0x4E4F534Au);
  EXPECT_EQ(json_len % 4, 0u);
  if (20 + static_cast<std::size_t>(json_len) > b.size()) return f;
  f.json = nlohmann::json::parse(b.begin() + 20, b.begin() + 20 + json_len, nullptr, false);
  EXPECT_FALSE(f.json.is_discarded());
  const std::size_t at = 20 + json_len;
  if (at + 8 <= b.size()) {
    const std::uint32_t bin_len = glbWord(b, at);
    EXPECT_EQ(glbWord(b, at + 4), 0x004E4942u);
    EXPECT_EQ(at + 8 + bin_len, b.size());
    if (at + 8 + bin_len <= b.size()) f.bin.assign(b.begin() + static_cast<long>(at + 8), b.end());
  }
  f.ok = !f.json.is_discarded();
  return f;
}

}  // namespace vistel::test
