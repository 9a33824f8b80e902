// ForceLog: the own avatar's contact force per body part, frame after frame (issue 25 item
// 10), as a CSV stream (vistel-client --forces-out FILE) and a summary for --stats-json.
//
// CSV: a header row, then one row per frame per part whose force is not zero, and one row
// of zeros when a part's force returns to zero (so a reader sees every release):
//   time_s,part,fx_n,fy_n,fz_n,magnitude_n,area_m2
//   12.3456,l_hand,0.0000,-1.2500,0.3100,1.2879,0.001234
// time: the caller's clock (the client's seconds since start); forces: newtons in the
// avatar's model space (+X its left, +Y up, +Z forward); area: m^2. Rows are flushed each
// frame that has any (a `tail -f` sees them live).
//
// Summary (json()): frames seen, frames with any contact, the largest total force, per part
// its frames in contact, peak and mean magnitude, and the last frame's forces.
//
// Not thread-safe; add() allocates nothing once the stream is open (fmt formats into a
// reused buffer).
#pragma once

#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "client/deform/part_forces.hpp"
#include "common/base/result.hpp"

namespace vistel {

class ForceLog {
 public:
  // part_names: the parts add() gets, in that order.
  explicit ForceLog(std::vector<std::string> part_names);
  ~ForceLog();
  ForceLog(const ForceLog&) = delete;
  ForceLog& operator=(const ForceLog&) = delete;

  // Starts the CSV stream (truncates the file, writes the header). Errors name the file.
  Status openCsv(const std::string& path);
  // One frame: forces has one entry per part (fewer: the rest count as zero). Returns the
  // file's error when a write fails (the stream is closed then; the summary goes on).
  Status add(double time, std::span<const PartForce> forces);
  // Closes the stream (flushing it). Idempotent.
  Status close();

  // The summary as one JSON member, "own_forces": {...}, keys indented by two spaces.
  std::string json() const;

  std::int64_t frames() const { return frames_; }
  std::int64_t rowsWritten() const { return rows_; }
  const std::vector<std::string>& partNames() const { return names_; }

 private:
  struct PartSummary {
    std::int64_t frames_in_contact = 0;
    double peak_n = 0.0;
    double sum_n = 0.0;
    PartForce last;
  };

  std::vector<std::string> names_;
  std::vector<std::string> csv_names_;     // (npart) as CSV fields (quoted when needed)
  std::vector<std::uint8_t> was_nonzero_;  // (npart) last frame's force was not zero
  std::vector<PartSummary> parts_;         // (npart)
  std::FILE* csv_ = nullptr;
  std::string path_;
  std::string line_;  // reused row buffer
  std::int64_t frames_ = 0;
  std::int64_t frames_in_contact_ = 0;
  std::int64_t rows_ = 0;
  double peak_total_n_ = 0.0;
  double last_time_ = 0.0;
};

}  // namespace vistel
