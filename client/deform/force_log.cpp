#include "client/deform/force_log.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iterator>

namespace vistel {
namespace {

// Part names come from avatar files: quoted where CSV or JSON would misread them.
std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string jsonString(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += fmt::format("\\u{:04x}", static_cast<int>(c));
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace

ForceLog::ForceLog(std::vector<std::string> part_names)
    : names_(std::move(part_names)),
      csv_names_(names_.size()),
      was_nonzero_(names_.size(), 0),
      parts_(names_.size()) {
  for (std::size_t i = 0; i < names_.size(); ++i) csv_names_[i] = csvField(names_[i]);
  line_.reserve(256);
}

ForceLog::~ForceLog() { (void)close(); }

Status ForceLog::openCsv(const std::string& path) {
  (void)close();
  path_ = path;
  csv_ = std::fopen(path.c_str(), "w");
  if (csv_ == nullptr) return fail("{}: cannot write ({})", path, std::strerror(errno));
  if (std::fputs("time_s,part,fx_n,fy_n,fz_n,magnitude_n,area_m2\n", csv_) < 0 ||
      std::fflush(csv_) != 0) {
    const std::string why = std::strerror(errno);
    std::fclose(csv_);
    csv_ = nullptr;
    return fail("{}: cannot write ({})", path, why);
  }
  return {};
}

Status ForceLog::close() {
  if (csv_ == nullptr) return {};
  const bool ok = std::fflush(csv_) == 0 && std::ferror(csv_) == 0;
  const std::string why = ok ? std::string() : std::strerror(errno);
  std::fclose(csv_);
  csv_ = nullptr;
  if (!ok) return fail("{}: write failed ({})", path_, why);
  return {};
}

Status ForceLog::add(double time, std::span<const PartForce> forces) {
  ++frames_;
  last_time_ = time;
  glm::dvec3 net(0.0);
  bool any_row = false;
  bool any_contact = false;
  for (std::size_t i = 0; i < names_.size(); ++i) {
    const PartForce f = i < forces.size() ? forces[i] : PartForce{};
    const bool nonzero = f.force != glm::vec3(0.0f);
    const double magnitude = glm::length(glm::dvec3(f.force));
    PartSummary& s = parts_[i];
    s.last = f;
    if (nonzero) {
      ++s.frames_in_contact;
      s.peak_n = std::max(s.peak_n, magnitude);
      s.sum_n += magnitude;
      net += glm::dvec3(f.force);
      any_contact = true;
    }
    // A row for a force, and for its return to zero.
    if (csv_ != nullptr && (nonzero || was_nonzero_[i] != 0)) {
      line_.clear();
      fmt::format_to(std::back_inserter(line_), "{:.4f},{},{:.4f},{:.4f},{:.4f},{:.4f},{:.6f}\n",
                     time, csv_names_[i], f.force.x, f.force.y, f.force.z, magnitude, f.area);
      if (std::fputs(line_.c_str(), csv_) < 0) {
        const std::string why = std::strerror(errno);
        std::fclose(csv_);
        csv_ = nullptr;
        return fail("{}: write failed ({}); --forces-out stopped", path_, why);
      }
      ++rows_;
      any_row = true;
    }
    was_nonzero_[i] = nonzero ? 1 : 0;
  }
  if (any_contact) ++frames_in_contact_;
  peak_total_n_ = std::max(peak_total_n_, glm::length(net));
  if (any_row && csv_ != nullptr && std::fflush(csv_) != 0) {
    const std::string why = std::strerror(errno);
    std::fclose(csv_);
    csv_ = nullptr;
    return fail("{}: write failed ({}); --forces-out stopped", path_, why);
  }
  return {};
}

std::string ForceLog::json() const {
  std::string parts;
  std::string last;
  for (std::size_t i = 0; i < names_.size(); ++i) {
    const PartSummary& s = parts_[i];
    if (s.frames_in_contact > 0) {
      parts += fmt::format(
          "{}\n      \"{}\": {{\"frames_in_contact\": {}, \"peak_n\": {:.4f}, \"mean_n\": {:.4f}}}",
          parts.empty() ? "" : ",", jsonString(names_[i]), s.frames_in_contact, s.peak_n,
          s.sum_n / static_cast<double>(s.frames_in_contact));
    }
    if (s.last.force != glm::vec3(0.0f)) {
      last += fmt::format(
          "{}\n        \"{}\": {{\"force_n\": [{:.4f}, {:.4f}, {:.4f}], \"magnitude_n\": {:.4f}, "
          "\"area_m2\": {:.6f}}}",
          last.empty() ? "" : ",", jsonString(names_[i]), s.last.force.x, s.last.force.y,
          s.last.force.z, glm::length(glm::dvec3(s.last.force)), s.last.area);
    }
  }
  return fmt::format(
      "  \"own_forces\": {{\n"
      "    \"space\": \"avatar model (+x left, +y up, +z forward), newtons\",\n"
      "    \"frames\": {},\n"
      "    \"frames_in_contact\": {},\n"
      "    \"peak_total_n\": {:.4f},\n"
      "    \"parts\": {{{}{}}},\n"
      "    \"last_frame\": {{\"time_s\": {:.4f}, \"parts\": {{{}{}}}}}\n"
      "  }}",
      frames_, frames_in_contact_, peak_total_n_, parts, parts.empty() ? "" : "\n    ", last_time_,
      last, last.empty() ? "" : "\n      ");
}

}  // namespace vistel
