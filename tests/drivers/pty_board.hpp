#pragma once

// A pseudo-terminal pair and a simulated board on its master side, for the serial drives'
// tests: the drive opens the slave path like a real /dev/ttyACM0.

#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <functional>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "flowsteer/base/unique_fd.hpp"

namespace flowsteer::drivers::testing {

class Pty {
 public:
  Pty() {
    master_.reset(::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC));
    if (!master_ || ::grantpt(master_.get()) != 0 || ::unlockpt(master_.get()) != 0) {
      throw std::runtime_error(std::string("posix_openpt: ") + std::strerror(errno));
    }
    char name[128];
    if (::ptsname_r(master_.get(), name, sizeof name) != 0) {
      throw std::runtime_error(std::string("ptsname_r: ") + std::strerror(errno));
    }
    slave_path_ = name;
    // Keep one slave descriptor open in raw mode so the master never reads EIO between the
    // drive's open() calls and no echo or line editing touches the bytes.
    slave_.reset(::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC));
    termios tio{};
    ::tcgetattr(slave_.get(), &tio);
    ::cfmakeraw(&tio);
    ::tcsetattr(slave_.get(), TCSANOW, &tio);
  }
  int master() const { return master_.get(); }
  const std::string& slave_path() const { return slave_path_; }
  // The board's end goes away, as when a USB adapter is pulled: closing both of the test's
  // descriptors leaves the drive's slave descriptor hung up (reads and writes fail with EIO).
  // The board must be stopped first.
  void hang_up() {
    master_.reset();
    slave_.reset();
  }

 private:
  base::UniqueFd master_;
  base::UniqueFd slave_;
  std::string slave_path_;
};

// Runs `serve` on its own thread until stopped; `serve` reads requests with read_byte().
class Board {
 public:
  explicit Board(const Pty& pty) : fd_(pty.master()) {}
  virtual ~Board() { stop(); }

  void start() {
    thread_ = std::thread([this] {
      try {
        while (!stopping_) {
          serve();
        }
      } catch (const Stopped&) {
        // stop() was called while waiting for a byte.
      }
    });
  }
  void stop() {
    stopping_ = true;
    if (thread_.joinable()) {
      thread_.join();
    }
  }
  // Problems the board found in what the drive sent; the test expects none.
  std::vector<std::string> errors() {
    std::lock_guard lock(mutex_);
    return errors_;
  }

 protected:
  virtual void serve() = 0;

  struct Stopped {};
  std::uint8_t read_byte() {
    for (;;) {
      if (stopping_) {
        throw Stopped{};
      }
      pollfd pfd{fd_, POLLIN, 0};
      if (::poll(&pfd, 1, 10) > 0 && (pfd.revents & POLLIN) != 0) {
        std::uint8_t b = 0;
        if (::read(fd_, &b, 1) == 1) {
          return b;
        }
      }
    }
  }
  void send(const std::vector<std::uint8_t>& bytes) {
    if (::write(fd_, bytes.data(), bytes.size()) != static_cast<ssize_t>(bytes.size())) {
      error("board: write failed");
    }
  }
  void send(const std::string& text) { send(std::vector<std::uint8_t>(text.begin(), text.end())); }
  void error(const std::string& what) {
    std::lock_guard lock(mutex_);
    errors_.push_back(what);
  }
  std::mutex mutex_;

 private:
  int fd_;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
  std::vector<std::string> errors_;
};

}  // namespace flowsteer::drivers::testing
