#include "flowsteer/drivers/serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "flowsteer/base/clock.hpp"
#include "flowsteer/drivers/drive.hpp"

namespace flowsteer::drivers {

namespace {

speed_t baud_constant(int baud) {
  switch (baud) {
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    case 460800:
      return B460800;
    case 921600:
      return B921600;
    default:
      return B0;
  }
}

std::string printable(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '\r') {
      out += "\\r";
    } else if (c == '\n') {
      out += "\\n";
    } else if (c >= 0x20 && c < 0x7f) {
      out += c;
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", static_cast<unsigned char>(c));
      out += buf;
    }
  }
  return out;
}

}  // namespace

std::string hex_bytes(std::span<const std::uint8_t> bytes) {
  std::string out;
  for (const std::uint8_t b : bytes) {
    char buf[8];
    std::snprintf(buf, sizeof buf, "%s0x%02x", out.empty() ? "" : " ", b);
    out += buf;
  }
  return out.empty() ? "nothing" : out;
}

SerialPort::SerialPort(const SerialConfig& config) : config_(config) {
  const std::string where = "serial " + config_.device;
  const speed_t speed = baud_constant(config_.baud);
  if (speed == B0) {
    throw DriveError(where + ": unsupported baud rate " + std::to_string(config_.baud));
  }
  if (!(config_.timeout_s > 0.0)) {
    throw DriveError(where + ": timeout_s must be > 0");
  }
  // Non-blocking, so that no read or write can wait past poll()'s timeout; no controlling
  // terminal, so a hang-up on the line cannot signal the process.
  fd_.reset(::open(config_.device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC));
  if (!fd_) {
    throw DriveError(where + ": open: " + std::strerror(errno));
  }
  termios tio{};
  if (::tcgetattr(fd_.get(), &tio) != 0) {
    throw DriveError(where + ": not a serial device (tcgetattr: " + std::strerror(errno) + ")");
  }
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | CRTSCTS);
  if (::cfsetispeed(&tio, speed) != 0 || ::cfsetospeed(&tio, speed) != 0) {
    throw DriveError(where + ": cfsetspeed: " + std::strerror(errno));
  }
  if (::tcsetattr(fd_.get(), TCSANOW, &tio) != 0) {
    throw DriveError(where + ": tcsetattr: " + std::strerror(errno));
  }
  discard_input();
}

bool SerialPort::wait(short events, double deadline_s, const char* operation) {
  for (;;) {
    const double left_s = deadline_s - base::monotonic_now_s();
    if (left_s <= 0.0) {
      return false;
    }
    pollfd pfd{fd_.get(), events, 0};
    const int ready = ::poll(&pfd, 1, static_cast<int>(left_s * 1000.0) + 1);
    if (ready < 0) {
      if (errno == EINTR) {
        continue;
      }
      throw DriveError("serial " + config_.device + ": poll during " + operation + ": " +
                       std::strerror(errno));
    }
    if (ready > 0) {
      if ((pfd.revents & (POLLERR | POLLNVAL)) != 0) {
        throw DriveError("serial " + config_.device + ": device error during " + operation);
      }
      // POLLHUP with data still buffered is fine; read() returns 0 once it is drained.
      return true;
    }
  }
}

void SerialPort::write_all(std::span<const std::uint8_t> bytes) {
  const double deadline_s = base::monotonic_now_s() + config_.timeout_s;
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_.get(), bytes.data() + done, bytes.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EINTR) {
      throw DriveError("serial " + config_.device + ": write: " + std::strerror(errno));
    }
    if (!wait(POLLOUT, deadline_s, "write")) {
      throw DriveError("serial " + config_.device + ": write timed out after " +
                       std::to_string(config_.timeout_s) + " s (" + std::to_string(done) + " of " +
                       std::to_string(bytes.size()) + " bytes sent)");
    }
  }
}

void SerialPort::write_all(const std::string& text) {
  write_all(std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

std::vector<std::uint8_t> SerialPort::read_exact(std::size_t n) {
  const double deadline_s = base::monotonic_now_s() + config_.timeout_s;
  std::vector<std::uint8_t> out(n);
  std::size_t done = 0;
  while (done < n) {
    const ssize_t got = ::read(fd_.get(), out.data() + done, n - done);
    if (got > 0) {
      done += static_cast<std::size_t>(got);
      continue;
    }
    if (got == 0) {
      out.resize(done);
      throw DriveError("serial " + config_.device + ": device closed (hang-up) after " +
                       hex_bytes(out) + " of " + std::to_string(n) + " expected bytes");
    }
    if (errno != EAGAIN && errno != EINTR) {
      throw DriveError("serial " + config_.device + ": read: " + std::strerror(errno));
    }
    if (!wait(POLLIN, deadline_s, "read")) {
      out.resize(done);
      throw DriveError("serial " + config_.device + ": short reply: timed out after " +
                       std::to_string(config_.timeout_s) + " s waiting for " + std::to_string(n) +
                       " bytes, got " + hex_bytes(out));
    }
  }
  return out;
}

std::string SerialPort::read_line(char terminator, std::size_t max_bytes) {
  const double deadline_s = base::monotonic_now_s() + config_.timeout_s;
  std::string line;
  // One byte at a time: the reply is short and whatever follows the terminator must stay in
  // the buffer for the next reply.
  for (;;) {
    char c = 0;
    const ssize_t got = ::read(fd_.get(), &c, 1);
    if (got == 1) {
      line += c;
      if (c == terminator) {
        return line;
      }
      if (line.size() >= max_bytes) {
        throw DriveError("serial " + config_.device + ": garbled reply: no end of line within " +
                         std::to_string(max_bytes) + " bytes: \"" + printable(line) + "\"");
      }
      continue;
    }
    if (got == 0) {
      throw DriveError("serial " + config_.device + ": device closed (hang-up) after \"" +
                       printable(line) + "\"");
    }
    if (errno != EAGAIN && errno != EINTR) {
      throw DriveError("serial " + config_.device + ": read: " + std::strerror(errno));
    }
    if (!wait(POLLIN, deadline_s, "read")) {
      throw DriveError("serial " + config_.device + ": short reply: timed out after " +
                       std::to_string(config_.timeout_s) + " s waiting for a line, got \"" +
                       printable(line) + "\"");
    }
  }
}

void SerialPort::discard_input() {
  if (::tcflush(fd_.get(), TCIFLUSH) != 0) {
    throw DriveError("serial " + config_.device + ": tcflush: " + std::strerror(errno));
  }
}

}  // namespace flowsteer::drivers
