#include "client/deform/own_forces.hpp"

#include <algorithm>

namespace vistel {

OwnForces::OwnForces(PartForceLayout layout)
    : layout_(std::move(layout)),
      forces_(layout_.names.size()),
      force_vectors_(layout_.names.size(), glm::vec3(0.0f)),
      log_(layout_.names) {}

Result<std::unique_ptr<OwnForces>> OwnForces::create(const AvatarModel& own,
                                                     const OwnForcesOptions& options) {
  return create(own, options, nullptr);
}

Result<std::unique_ptr<OwnForces>> OwnForces::create(const AvatarModel& own,
                                                     const OwnForcesOptions& options,
                                                     std::unique_ptr<HidOutputDevice> device) {
  Result<PartForceLayout> layout = makePartForceLayout(own);
  if (!layout) return withContext("own contact forces", layout.error());
  std::unique_ptr<OwnForces> out(new OwnForces(std::move(*layout)));
  if (!options.csv_path.empty()) {
    if (Status st = out->log_.openCsv(options.csv_path); !st) {
      return withContext("--forces-out", st.error());
    }
  }
  // The force-feedback device of the sensors config, when it names one.
  if (!options.force_feedback_config.empty()) {
    Result<SensorSetup> setup = loadSensorSetup(options.force_feedback_config);
    if (!setup) return setup.error();
    const ForceFeedbackConfig& ff = setup->force_feedback;
    if (!ff.enabled) {
      if (device || options.require_force_feedback) {
        out->warnings_.push_back(fmt::format("{}: no [force_feedback] section; no device driven",
                                             options.force_feedback_config));
      }
    } else {
      // Channels naming parts the avatar lacks: a warning each (they send 0).
      std::vector<std::string> unknown;
      (void)bindForceChannels(ff, out->layout_.names, &unknown);
      for (const std::string& part : unknown) {
        std::string known;
        for (const std::string& n : out->layout_.names) known += (known.empty() ? "" : ", ") + n;
        out->warnings_.push_back(fmt::format(
            "{}: force_feedback.channel part '{}' is not a body part of avatar '{}' (its "
            "parts: {}); that channel sends 0",
            options.force_feedback_config, part, own.name, known));
      }
      if (!device) {
        Result<std::unique_ptr<HidOutputDevice>> opened = openHidapiOutput(ff);
        if (opened) {
          device = std::move(*opened);
        } else {
          out->warnings_.push_back(fmt::format(
              "{}: {}; no force feedback", options.force_feedback_config, opened.error().message));
        }
      }
      if (device) {
        const double rate = std::min(ff.max_rate_hz, options.frame_rate_hz);
        out->device_ =
            std::make_unique<ForceFeedbackWriter>(std::move(device), ff, out->layout_.names, rate);
      }
    }
  }
  return out;
}

Status OwnForces::frame(double now, const RoomDeformer* deformer,
                        std::optional<std::uint32_t> self_view) {
  // This frame's forces (zero when the own body was not deformed).
  std::optional<PartForceInput> input;
  if (deformer != nullptr && self_view) input = deformer->partForceInput(*self_view);
  if (input) {
    computePartForces(layout_, *input, forces_);
  } else {
    std::fill(forces_.begin(), forces_.end(), PartForce{});
  }
  for (std::size_t i = 0; i < forces_.size(); ++i) force_vectors_[i] = forces_[i].force;
  // On to the log and the device.
  Status status = log_.add(now, forces_);
  if (device_) {
    if (Status st = device_->update(now, force_vectors_); !st && status) status = st;
  }
  return status;
}

Status OwnForces::close() {
  if (device_) device_->close();
  return log_.close();
}

std::string OwnForces::summary() const {
  return fmt::format(
      "own contact forces: {} frames, {} CSV rows{}", log_.frames(), log_.rowsWritten(),
      device_ ? fmt::format(", {} reports to {}", device_->reportsSent(), device_->describe())
              : std::string());
}

}  // namespace vistel
