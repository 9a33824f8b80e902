// Prometheus text exposition format 0.0.4 (server/http/prometheus), and the Agones
// label and port checks (server/http/agones_sdk).
#include "server/http/prometheus.hpp"

#include <cstdlib>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "server/http/agones_sdk.hpp"

namespace vistel::server {
namespace {

TEST(Prometheus, EscapesLabelValuesAndHelp) {
  EXPECT_EQ(escapeLabelValue(R"(a"b\c)"), R"(a\"b\\c)");
  EXPECT_EQ(escapeLabelValue("line\nnext"), "line\\nnext");
  EXPECT_EQ(escapeLabelValue("plain é"), "plain é");
  EXPECT_EQ(escapeHelp("a \"quoted\" \\ help\nline"), "a \"quoted\" \\\\ help\\nline");
}

TEST(Prometheus, SanitizesNames) {
  EXPECT_EQ(sanitizeMetricName("vistel_tick:seconds"), "vistel_tick:seconds");
  EXPECT_EQ(sanitizeMetricName("bad-name.x"), "bad_name_x");
  EXPECT_EQ(sanitizeMetricName("9lives"), "_9lives");
  EXPECT_EQ(sanitizeMetricName(""), "_");
  EXPECT_EQ(sanitizeLabelName("a:b"), "a_b");
  EXPECT_EQ(sanitizeLabelName("__reserved"), "x__reserved");
}

TEST(Prometheus, SpellsValues) {
  EXPECT_EQ(formatSampleValue(3.0), "3");
  EXPECT_EQ(formatSampleValue(0.25), "0.25");
  EXPECT_EQ(formatSampleValue(1e-4), "0.0001");
  EXPECT_EQ(formatSampleValue(std::numeric_limits<double>::infinity()), "+Inf");
  EXPECT_EQ(formatSampleValue(-std::numeric_limits<double>::infinity()), "-Inf");
  EXPECT_EQ(formatSampleValue(std::numeric_limits<double>::quiet_NaN()), "NaN");
  EXPECT_EQ(formatSampleValue(12345678901.0), "12345678901");
}

TEST(Prometheus, WritesCountersGaugesAndHistograms) {
  std::vector<MetricFamily> families;
  families.push_back({"req_total",
                      "Requests.",
                      MetricType::kCounter,
                      {{{{"code", "200"}, {"path", "/a\"b"}}, 7, {}}, {{}, 1, {}}}});
  families.push_back({"temp", "Temperature\nin C.", MetricType::kGauge, {{{}, -1.5, {}}}});
  HistogramData h;
  h.upper_bounds = {0.1, 1.0};
  h.bucket_counts = {2, 3, 1};
  h.count = 6;
  h.sum = 4.5;
  families.push_back(
      {"lat_seconds", "Latency.", MetricType::kHistogram, {{{{"room", "a"}}, 0, h}}});
  families.push_back({"empty_total", "No samples yet.", MetricType::kCounter, {}});

  EXPECT_EQ(formatPrometheus(families),
            "# HELP req_total Requests.\n"
            "# TYPE req_total counter\n"
            "req_total{code=\"200\",path=\"/a\\\"b\"} 7\n"
            "req_total 1\n"
            "# HELP temp Temperature\\nin C.\n"
            "# TYPE temp gauge\n"
            "temp -1.5\n"
            "# HELP lat_seconds Latency.\n"
            "# TYPE lat_seconds histogram\n"
            "lat_seconds_bucket{room=\"a\",le=\"0.1\"} 2\n"
            "lat_seconds_bucket{room=\"a\",le=\"1\"} 5\n"
            "lat_seconds_bucket{room=\"a\",le=\"+Inf\"} 6\n"
            "lat_seconds_sum{room=\"a\"} 4.5\n"
            "lat_seconds_count{room=\"a\"} 6\n"
            "# HELP empty_total No samples yet.\n"
            "# TYPE empty_total counter\n");
}

TEST(Prometheus, HistogramWithoutLabelsHasOnlyLe) {
  HistogramData h;
  h.upper_bounds = {1.0};
  h.bucket_counts = {0, 0};
  MetricFamily f{"h", "x", MetricType::kHistogram, {{{}, 0, h}}};
  std::string text = formatPrometheus(std::span<const MetricFamily>(&f, 1));
  EXPECT_NE(text.find("h_bucket{le=\"1\"} 0\n"), std::string::npos);
  EXPECT_NE(text.find("h_bucket{le=\"+Inf\"} 0\n"), std::string::npos);
  EXPECT_NE(text.find("h_sum 0\n"), std::string::npos);
  EXPECT_NE(text.find("h_count 0\n"), std::string::npos);
}

TEST(Prometheus, AtomicHistogramBucketsAreInclusiveAndSumInSeconds) {
  AtomicHistogram h({0.001, 0.002});
  h.observe(0.0005);
  h.observe(0.001);  // on the bound: first bucket (le is inclusive)
  h.observe(0.0015);
  h.observe(0.5);   // +Inf bucket
  h.observe(-1.0);  // first bucket, adds nothing to the sum
  HistogramData d = h.snapshot();
  ASSERT_EQ(d.bucket_counts.size(), 3u);
  EXPECT_EQ(d.bucket_counts[0], 3u);
  EXPECT_EQ(d.bucket_counts[1], 1u);
  EXPECT_EQ(d.bucket_counts[2], 1u);
  EXPECT_EQ(d.count, 5u);
  EXPECT_NEAR(d.sum, 0.503, 1e-9);
}

TEST(Prometheus, AtomicHistogramCountsFromSeveralThreads) {
  AtomicHistogram h(defaultTickBuckets());
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&h, t] {
      for (int i = 0; i < 10000; ++i) h.observe(0.0001 * (1 + (i + t) % 50));
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(h.snapshot().count, 40000u);
}

bool isNameChar(char c, bool first, bool colon) {
  bool alpha = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || (colon && c == ':');
  return alpha || (!first && c >= '0' && c <= '9');
}

// Reads a metric or label name at `at`; empty when there is none.
std::string readName(const std::string& line, std::size_t& at, bool colon) {
  std::size_t start = at;
  while (at < line.size() && isNameChar(line[at], at == start, colon)) ++at;
  return line.substr(start, at - start);
}

// A sample line of the 0.0.4 grammar: name{label="escaped",...} value. Sets name, value.
bool parseSampleLine(const std::string& line, std::string& name, double& value) {
  std::size_t at = 0;
  name = readName(line, at, true);
  if (name.empty()) return false;
  if (at < line.size() && line[at] == '{') {
    ++at;
    while (at < line.size() && line[at] != '}') {
      if (readName(line, at, false).empty()) return false;
      if (line.compare(at, 2, "=\"") != 0) return false;
      at += 2;
      while (at < line.size() && line[at] != '"') {
        if (line[at] == '\\') {
          if (at + 1 >= line.size() ||
              std::string("\\\"n").find(line[at + 1]) == std::string::npos) {
            return false;
          }
          ++at;
        }
        ++at;
      }
      if (at >= line.size()) return false;
      ++at;  // closing quote
      if (at < line.size() && line[at] == ',') ++at;
    }
    if (at >= line.size()) return false;
    ++at;  // '}'
  }
  if (at >= line.size() || line[at] != ' ') return false;
  std::string text = line.substr(at + 1);
  if (text == "+Inf" || text == "-Inf" || text == "NaN") {
    value = 0;
    return true;
  }
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size();
}

// Every line of a full scrape follows the 0.0.4 grammar, each family has exactly one HELP
// and one TYPE line before its samples, and histogram buckets are cumulative.
TEST(Prometheus, SnapshotScrapeIsWellFormed) {
  {  // the line checker itself
    std::string n;
    double v = 0;
    EXPECT_TRUE(parseSampleLine("x{a=\"q\\\"\",b=\"\"} 2", n, v));
    EXPECT_EQ(v, 2);
    EXPECT_FALSE(parseSampleLine("x{a=\"b} 1", n, v));
    EXPECT_FALSE(parseSampleLine("x{a=b} 1", n, v));
    EXPECT_FALSE(parseSampleLine("1x 1", n, v));
    EXPECT_FALSE(parseSampleLine("x 1z", n, v));
    EXPECT_FALSE(parseSampleLine("x{a=\"\\t\"} 1", n, v));
  }
  MetricsSnapshot s;
  s.ready = true;
  s.members = 12;
  s.rooms = 2;
  s.connections = 13;
  s.ticks_total = 600;
  AtomicHistogram ticks(defaultTickBuckets());
  for (int i = 0; i < 100; ++i) ticks.observe(0.0001 * i);
  s.tick_seconds = ticks.snapshot();
  s.bytes_in_udp = 1000;
  s.datagrams_dropped = {{"bad key", 3}, {"unknown \"member\"", 1}};
  s.joins_refused = {{"SERVER_FULL", 65}};
  s.extra.push_back({"vistel_custom", "Custom.", MetricType::kGauge, {{{}, 1, {}}}});
  std::string text = formatMetrics(s);

  std::set<std::string> helped, typed;
  std::string current;
  std::istringstream lines(text);
  std::string line;
  double previous_bucket = -1;
  int lines_seen = 0;
  while (std::getline(lines, line)) {
    ++lines_seen;
    if (line.rfind("# HELP ", 0) == 0) {
      std::size_t at = 7;
      std::string name = readName(line, at, true);
      ASSERT_FALSE(name.empty()) << line;
      ASSERT_EQ(line[at], ' ') << line;
      EXPECT_TRUE(helped.insert(name).second) << "second HELP for " << name;
      current = name;
      previous_bucket = -1;
    } else if (line.rfind("# TYPE ", 0) == 0) {
      std::size_t at = 7;
      std::string name = readName(line, at, true);
      EXPECT_EQ(name, current);
      std::string kind = line.substr(at);
      EXPECT_TRUE(kind == " counter" || kind == " gauge" || kind == " histogram") << line;
      EXPECT_TRUE(typed.insert(name).second);
    } else {
      std::string name;
      double v = 0;
      ASSERT_TRUE(parseSampleLine(line, name, v)) << "bad line: " << line;
      EXPECT_EQ(name.rfind(current, 0), 0u) << name << " outside its family " << current;
      if (name == "vistel_tick_seconds_bucket" && line.find("+Inf") == std::string::npos) {
        EXPECT_GE(v, previous_bucket) << "buckets must be cumulative";
        previous_bucket = v;
      }
    }
  }
  EXPECT_GT(lines_seen, 30);
  for (const char* family :
       {"vistel_ready", "vistel_members", "vistel_rooms", "vistel_connections",
        "vistel_ticks_total", "vistel_tick_seconds", "vistel_received_bytes_total",
        "vistel_sent_bytes_total", "vistel_datagrams_dropped_total", "vistel_joins_refused_total",
        "vistel_custom"}) {
    EXPECT_TRUE(helped.count(family)) << family;
    EXPECT_TRUE(typed.count(family)) << family;
  }
  EXPECT_NE(text.find("vistel_members 12\n"), std::string::npos);
  EXPECT_NE(text.find("vistel_ready 1\n"), std::string::npos);
  EXPECT_NE(text.find("vistel_received_bytes_total{transport=\"udp\"} 1000\n"), std::string::npos);
  EXPECT_NE(text.find("vistel_datagrams_dropped_total{reason=\"unknown \\\"member\\\"\"} 1\n"),
            std::string::npos);
  EXPECT_NE(text.find("vistel_joins_refused_total{reason=\"SERVER_FULL\"} 65\n"),
            std::string::npos);
  EXPECT_NE(text.find("vistel_tick_seconds_bucket{le=\"+Inf\"} 100\n"), std::string::npos);
  EXPECT_NE(text.find("vistel_tick_seconds_count 100\n"), std::string::npos);
}

TEST(AgonesChecks, ValidatesLabels) {
  EXPECT_TRUE(validateAgonesLabel("vistel-room", "lobby"));
  EXPECT_TRUE(validateAgonesLabel("vistel.version", "0.1.0"));
  EXPECT_TRUE(validateAgonesLabel("ready", ""));
  EXPECT_FALSE(validateAgonesLabel("", "x"));
  EXPECT_FALSE(validateAgonesLabel("has space", "x"));
  EXPECT_FALSE(validateAgonesLabel("a/b", "x"));
  EXPECT_FALSE(validateAgonesLabel("trailing-", "x"));
  EXPECT_FALSE(validateAgonesLabel(std::string(60, 'k'), "x"));  // "sdk-" + 60 > 63
  EXPECT_TRUE(validateAgonesLabel(std::string(59, 'k'), "x"));
  EXPECT_FALSE(validateAgonesLabel("k", std::string(64, 'v')));
  EXPECT_FALSE(validateAgonesLabel("k", "-v"));
  EXPECT_FALSE(validateAgonesLabel("k", "room \"x\""));
}

TEST(AgonesChecks, ParsesPortsAndTheEnvironment) {
  EXPECT_EQ(*parsePort("9358"), 9358);
  EXPECT_EQ(*parsePort("65535"), 65535);
  EXPECT_FALSE(parsePort("0"));
  EXPECT_FALSE(parsePort("65536"));
  EXPECT_FALSE(parsePort("-1"));
  EXPECT_FALSE(parsePort(" 80"));
  EXPECT_FALSE(parsePort("80x"));
  EXPECT_FALSE(parsePort(""));

  ::unsetenv("AGONES_SDK_HTTP_PORT");
  EXPECT_EQ(agonesOptionsFromEnvironment()->port, 9358);
  ::setenv("AGONES_SDK_HTTP_PORT", "59358", 1);
  EXPECT_EQ(agonesOptionsFromEnvironment()->port, 59358);
  ::setenv("AGONES_SDK_HTTP_PORT", "nope", 1);
  auto bad = agonesOptionsFromEnvironment();
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("AGONES_SDK_HTTP_PORT"), std::string::npos);
  ::unsetenv("AGONES_SDK_HTTP_PORT");
}

}  // namespace
}  // namespace vistel::server
