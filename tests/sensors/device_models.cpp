#include "tests/sensors/device_models.hpp"

#include <charconv>

namespace vistel::test {

FastrakModel::FastrakModel(std::function<FastrakRecord(int, double)> pose, double rate_hz)
    : pose_(std::move(pose)), period_(1.0 / rate_hz) {}

void FastrakModel::receive(std::string_view bytes, double now, Pieces& out) {
  pending_.append(bytes);
  // Commands: one letter, or a letter with parameters up to CR.
  for (;;) {
    if (pending_.empty()) return;
    const char c = pending_[0];
    if (c == 'O' || c == 'l' || c == 'x' || c == 'v' || c == 'H' || c == 'R' || c == 'A') {
      const std::size_t cr = pending_.find('\r');
      if (cr == std::string::npos) {
        if (pending_.size() > 200) pending_.clear();
        return;
      }
      const std::string cmd = pending_.substr(0, cr);
      pending_.erase(0, cr + 1);
      command(cmd, now, out);
    } else {
      pending_.erase(0, 1);
      command(std::string(1, c), now, out);
    }
  }
}

void FastrakModel::command(const std::string& cmd, double now, Pieces& out) {
  log_ += cmd[0];
  // Comma-separated integers after the letter.
  std::vector<int> args;
  for (std::size_t i = 1; i < cmd.size();) {
    int v = 0;
    const auto [end, ec] = std::from_chars(cmd.data() + i, cmd.data() + cmd.size(), v);
    if (ec != std::errc()) break;
    args.push_back(v);
    i = static_cast<std::size_t>(end - cmd.data()) + 1;
  }
  switch (cmd[0]) {
    case 'c':
      continuous_ = false;
      break;
    case 'C':
      continuous_ = true;
      next_ = now;
      break;
    case 'f':
      format_.encoding = FastrakEncoding::kBinary;
      break;
    case 'F':
      format_.encoding = FastrakEncoding::kAscii;
      break;
    case 'U':
      format_.units = LengthUnit::kInches;
      break;
    case 'u':
      format_.units = LengthUnit::kCentimetres;
      break;
    case 'P':
      ++polls_;
      records(now, out);
      break;
    case 'S': {
      std::string s = "21S";
      s += std::string(50, ' ');
      s.replace(4, 12, "status: OK  ");
      s += "\r\n";
      out.push_back(s);
      break;
    }
    case 'l':
      if (args.size() == 2 && args[0] >= 1 && args[0] <= 4)
        enabled_[static_cast<std::size_t>(args[0])] = args[1] != 0;
      break;
    case 'O':
      if (args.size() >= 2) {
        format_.items.clear();
        for (std::size_t i = 1; i < args.size(); ++i) {
          if (auto item = fastrakItemFromCode(args[i])) format_.items.push_back(*item);
        }
      }
      break;
    default:
      break;
  }
}

void FastrakModel::records(double now, Pieces& out) {
  for (int st = 1; st <= 4; ++st) {
    if (!enabled_[static_cast<std::size_t>(st)]) continue;
    FastrakRecord r = pose_(st, now);
    r.station = st;
    std::string rec;
    encodeFastrakRecord(r, format_, rec);
    out.push_back(rec);
  }
}

void FastrakModel::tick(double now, Pieces& out) {
  if (!continuous_) return;
  // A cycle of all enabled stations every 4 periods (120 Hz shared by 4).
  while (next_ <= now) {
    records(next_, out);
    next_ += 4 * period_;
  }
}

GloveModel::GloveModel(int hardware_sensors,
                       std::function<std::array<std::uint8_t, 22>(double)> raw, double rate_hz)
    : raw_(std::move(raw)), period_(1.0 / rate_hz) {
  format_.sensor_count = hardware_sensors;
}

void GloveModel::sample(double now, Pieces& out) {
  if (!plugged_) {
    out.push_back(std::string("eg\0", 3));
    return;
  }
  if (sampling_error_) {
    out.push_back(std::string("es\0", 3));
    return;
  }
  GloveRecord r;
  r.sensor_count = format_.sensor_count;
  const auto raw = raw_(now);
  std::copy(raw.begin(), raw.end(), r.raw.begin());
  r.timestamp = static_cast<std::uint64_t>(now * 1000.0);
  r.status = 3;
  std::string rec;
  encodeGloveRecord(r, format_, rec);
  out.push_back(rec);
}

void GloveModel::receive(std::string_view bytes, double now, Pieces& out) {
  pending_.append(bytes);
  for (;;) {
    if (pending_.empty()) return;
    const char c = pending_[0];
    std::size_t need = 1;
    if (c == '?' || c == '^' || c == 'N' || c == 'D' || c == 'U') need = 2;
    if (pending_.size() < need) return;
    const std::string cmd = pending_.substr(0, need);
    pending_.erase(0, need);
    if (cmd == "G") {
      sample(now, out);
    } else if (cmd == "S") {
      streaming_ = true;
      next_ = now;
    } else if (cmd == "^c" || cmd == "\x03") {
      streaming_ = false;
    } else if (cmd == "?N") {
      out.push_back(std::string("?N") + static_cast<char>(format_.sensor_count) + '\0');
    } else if (cmd == "?S") {
      out.push_back(std::string("?S") + static_cast<char>(22) + '\0');
    } else if (cmd[0] == 'N') {
      const int n = static_cast<std::uint8_t>(cmd[1]);
      if (n == 18 || n == 22) format_.sensor_count = n;
      out.push_back(std::string("N\0", 2));
    } else if (cmd[0] == 'D') {
      format_.timestamp = cmd[1] != 0;
      out.push_back(std::string("D\0", 2));
    } else if (cmd[0] == 'U') {
      format_.status_byte = cmd[1] != 0;
      out.push_back(std::string("U\0", 2));
    }
  }
}

void GloveModel::tick(double now, Pieces& out) {
  if (!streaming_) return;
  while (next_ <= now) {
    sample(next_, out);
    next_ += period_;
  }
}

}  // namespace vistel::test
