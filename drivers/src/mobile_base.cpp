#include "flowsteer/drivers/mobile_base.hpp"

#include <stdexcept>
#include <utility>

namespace flowsteer::drivers {

namespace {

const char* lifecycle_name(Lifecycle lifecycle) {
  switch (lifecycle) {
    case Lifecycle::unconfigured:
      return "unconfigured";
    case Lifecycle::inactive:
      return "inactive";
    case Lifecycle::active:
      return "active";
    case Lifecycle::failed:
      return "failed";
  }
  return "unknown";
}

}  // namespace

MobileBase::MobileBase(std::unique_ptr<Drive> drive, const CommandStageConfig& config)
    : drive_(std::move(drive)), stage_(config) {
  if (!drive_) {
    throw std::invalid_argument("base: no drive given");
  }
}

MobileBase::~MobileBase() {
  if (lifecycle_ == Lifecycle::active) {
    try {
      drive_->deactivate();
    } catch (const std::exception&) {
      // Nothing to report to: the drive already tried to stop before throwing.
    }
  }
}

void MobileBase::require(Lifecycle expected, const char* operation) const {
  if (lifecycle_ != expected) {
    throw DriveError(std::string(drive_->name()) + ": " + operation + " needs the base " +
                     lifecycle_name(expected) + ", it is " + lifecycle_name(lifecycle_));
  }
}

void MobileBase::fail(const std::string& during, const std::exception& error) {
  lifecycle_ = Lifecycle::failed;
  // The link may be what failed: then the zero cannot reach the wheels, and the message must
  // not claim it did (deactivate() below still tries its own way).
  std::string outcome = "base stopped";
  try {
    drive_->write({});
  } catch (const std::exception& e) {
    outcome = "the stop could not be sent either";
    if (std::string(e.what()) != error.what()) {
      outcome += std::string(" (") + e.what() + ")";
    }
  }
  try {
    drive_->deactivate();
  } catch (const std::exception&) {
    // Already failing: the first error is the one worth reporting.
  }
  throw DriveError(std::string(drive_->name()) + ": " + during + " failed, " + outcome + ": " +
                   error.what());
}

void MobileBase::configure() {
  if (lifecycle_ != Lifecycle::unconfigured && lifecycle_ != Lifecycle::failed) {
    require(Lifecycle::unconfigured, "configure");
  }
  try {
    drive_->configure();
  } catch (const std::exception& e) {
    lifecycle_ = Lifecycle::failed;
    throw DriveError(std::string(drive_->name()) + ": configure failed: " + e.what());
  }
  lifecycle_ = Lifecycle::inactive;
}

void MobileBase::activate(double now_s) {
  require(Lifecycle::inactive, "activate");
  stage_.reset(now_s);
  try {
    drive_->activate();
  } catch (const std::exception& e) {
    fail("activate", e);
  }
  lifecycle_ = Lifecycle::active;
}

void MobileBase::deactivate() {
  require(Lifecycle::active, "deactivate");
  try {
    drive_->deactivate();
  } catch (const std::exception& e) {
    fail("deactivate", e);
  }
  lifecycle_ = Lifecycle::inactive;
}

std::optional<std::string> MobileBase::command(const base::Command& command, double now_s) {
  return stage_.command(command, now_s);
}

BaseState MobileBase::update(double now_s) {
  require(Lifecycle::active, "update");
  BaseState state;
  state.sent = stage_.update(now_s);
  try {
    drive_->write(state.sent.wheels);
    state.drive = drive_->read();
  } catch (const std::exception& e) {
    fail("update", e);
  }
  state.measured = from_wheels(state.drive.measured, stage_.config().geometry);
  return state;
}

void MobileBase::emergency_stop() {
  stage_.emergency_stop();
  if (lifecycle_ == Lifecycle::active) {
    try {
      drive_->write({});
    } catch (const std::exception& e) {
      fail("emergency stop", e);
    }
  }
}

void MobileBase::clear_emergency_stop() {
  stage_.clear_emergency_stop();
}

}  // namespace flowsteer::drivers
