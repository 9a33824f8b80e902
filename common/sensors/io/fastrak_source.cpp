#include "common/sensors/io/fastrak_source.hpp"

#include <algorithm>
#include <thread>

namespace vistel {

SourceClock steadySeconds() {
  const auto start = std::chrono::steady_clock::now();
  return [start]() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
}

FastrakSource::FastrakSource(std::unique_ptr<ByteTransport> transport, const TrackerConfig& config,
                             SourceClock clock)
    : transport_(std::move(transport)),
      config_(config),
      clock_(std::move(clock)),
      parser_(config.format) {
  site_of_station_.fill(-1);
  for (const StationMapping& m : config_.stations) {
    if (m.station >= 1 && m.station <= kFastrakMaxStations)
      site_of_station_[m.station] = static_cast<int>(m.site);
  }
}

Result<std::unique_ptr<FastrakSource>> FastrakSource::open(std::unique_ptr<ByteTransport> transport,
                                                           const TrackerConfig& config,
                                                           SourceClock clock) {
  if (Status s = validateFastrakFormat(config.format); !s) {
    return withContext(transport->describe(), s.error());
  }
  if (config.stations.empty()) return fail("{}: no stations configured", transport->describe());
  std::unique_ptr<FastrakSource> src(
      new FastrakSource(std::move(transport), config, std::move(clock)));
  if (Status s = src->initialise(); !s) return s.error();
  return src;
}

IoResult FastrakSource::send(std::string_view command) {
  IoResult r = transport_->write(bytesOf(command), config_.reply_timeout_s);
  if (r.status != IoStatus::kOk)
    r.message = fmt::format("tracker: sending '{}': {}", command.substr(0, 1), r.message);
  return r;
}

Status FastrakSource::initialise() {
  const std::string where = transport_->describe();
  // Quiet the unit and drain what it was sending.
  if (IoResult r = send(kFastrakContinuousOff); r.status != IoStatus::kOk) return Error{r.message};
  const double drain_until = clock_() + 0.2;
  while (clock_() < drain_until) {
    const IoResult r = transport_->read(buffer_, 0.05);
    if (r.status == IoStatus::kUnplugged || r.status == IoStatus::kFailed)
      return fail("tracker: {}", r.message);
    if (r.status == IoStatus::kTimeout) break;
  }
  transport_->discardInput();

  // The status record proves a unit answers on this port at this speed.
  if (config_.check_status) {
    if (IoResult r = send(kFastrakStatusRequest); r.status != IoStatus::kOk)
      return Error{r.message};
    std::string reply;
    const double deadline = clock_() + config_.reply_timeout_s;
    bool found = false;
    while (!found) {
      const double left = deadline - clock_();
      if (left <= 0.0) break;
      const IoResult r = transport_->read(buffer_, left);
      if (r.status == IoStatus::kUnplugged || r.status == IoStatus::kFailed)
        return fail("tracker: {}", r.message);
      if (r.status == IoStatus::kTimeout) break;
      reply.append(reinterpret_cast<const char*>(buffer_.data()), r.bytes);
      // A status record: '2', a station, 'S', ... ending in LF.
      for (std::size_t i = 0; i + 2 < reply.size() && !found; ++i) {
        if (reply[i] == '2' && reply[i + 2] == 'S' && reply.find('\n', i) != std::string::npos)
          found = true;
      }
      if (reply.size() > 4096) reply.erase(0, reply.size() - 64);
    }
    if (!found) {
      return fail(
          "tracker on {}: no status reply to 'S' within {} s (is it powered, on this port, "
          "at {} baud?)",
          where, config_.reply_timeout_s, config_.baud);
    }
  }

  std::vector<int> stations;
  for (const StationMapping& m : config_.stations) {
    if (m.station >= 1 && m.station <= kFastrakMaxStations) stations.push_back(m.station);
  }
  for (const std::string& cmd : fastrakInitCommands(config_.format, stations, config_.continuous)) {
    if (IoResult r = send(cmd); r.status != IoStatus::kOk) return Error{r.message};
  }
  parser_.reset();
  return {};
}

IoResult FastrakSource::pump(double timeout_s, int& applied) {
  const IoResult r = transport_->read(buffer_, timeout_s);
  if (r.status != IoStatus::kOk) return r;
  parser_.feed(std::span<const std::uint8_t>(buffer_.data(), r.bytes));
  const double now = clock_();
  FastrakRecord rec;
  while (parser_.next(rec)) {
    const int site = site_of_station_[static_cast<std::size_t>(rec.station)];
    if (site < 0) {
      ++unknown_station_;
      continue;
    }
    StationReading& s = state_.stations[static_cast<std::size_t>(site)];
    const TransmitterPlacement& t = config_.transmitter;
    s.position = t.rotation * rec.position + t.position;
    s.orientation = glm::normalize(t.rotation * rec.orientation);
    s.status = rec.status;
    s.time = now;
    s.valid = true;
    heard_ |= 1u << rec.station;
    ++applied;
  }
  return r;
}

PollResult FastrakSource::poll(double timeout_s, SensorFrame& frame) {
  const double deadline = clock_() + std::max(0.0, timeout_s);
  unsigned wanted = 0;
  for (const StationMapping& m : config_.stations) {
    if (m.station >= 1 && m.station <= kFastrakMaxStations) wanted |= 1u << m.station;
  }
  if (!config_.continuous) {
    heard_ = 0;
    if (IoResult r = send(kFastrakPoll); r.status != IoStatus::kOk) {
      return r.status == IoStatus::kUnplugged ? PollResult::unplugged(r.message)
                                              : PollResult::failed(r.message);
    }
  }
  int applied = 0;
  for (;;) {
    const double left = deadline - clock_();
    const IoResult r = pump(std::max(0.0, left), applied);
    if (r.status == IoStatus::kUnplugged)
      return PollResult::unplugged(fmt::format("tracker: {}", r.message));
    if (r.status == IoStatus::kFailed)
      return PollResult::failed(fmt::format("tracker: {}", r.message));
    const bool complete = config_.continuous ? applied > 0 : (heard_ & wanted) == wanted;
    if (complete) {
      // Take whatever else is already waiting, so the frame is the newest.
      while (pump(0.0, applied).status == IoStatus::kOk) {
      }
      break;
    }
    if (r.status == IoStatus::kTimeout || clock_() >= deadline) {
      if (applied > 0) break;  // polled: a partial answer still updates what it can
      return PollResult::timeout(fmt::format("tracker on {}: no record within {:.3f} s",
                                             transport_->describe(), timeout_s));
    }
  }
  state_.time = clock_();
  state_.sequence = ++sequence_;
  // Keep the caller's gloves: this source owns only the stations.
  frame.time = state_.time;
  frame.sequence = state_.sequence;
  frame.stations = state_.stations;
  return PollResult::frame();
}

std::string FastrakSource::describe() const {
  return fmt::format("fastrak on {} ({}, {}, {} stations)", transport_->describe(),
                     config_.format.encoding == FastrakEncoding::kBinary ? "binary" : "ascii",
                     config_.continuous ? "continuous" : "polled", config_.stations.size());
}

}  // namespace vistel
