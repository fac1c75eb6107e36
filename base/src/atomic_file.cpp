#include "flowsteer/base/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>
#include <vector>

namespace flowsteer::base {

namespace {

std::runtime_error write_error(const std::filesystem::path& path, const char* what, int error) {
  return std::runtime_error("cannot write " + path.string() + ": " + what + ": " +
                            std::strerror(error));
}

}  // namespace

void write_file_atomically(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";
  // Appended piece by piece: GCC 12 warns (-Wrestrict, falsely) on "." + std::string.
  std::string file_name = ".";
  file_name += path.filename().string();
  file_name += ".tmp-XXXXXX";
  const std::string pattern = (dir / file_name).string();
  std::vector<char> name(pattern.begin(), pattern.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) {
    throw write_error(path, "cannot create a temporary file in its folder", errno);
  }
  const std::filesystem::path temporary(name.data());
  auto fail = [&](const char* what) {
    const int error = errno;
    ::close(fd);
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    return write_error(path, what, error);
  };
  std::size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0) {
      if (errno == EINTR) {
        continue;
      }
      throw fail("write failed");
    }
    written += static_cast<std::size_t>(n);
  }
  // mkstemp creates the file readable by its owner only; a calibration file is for everyone.
  if (::fchmod(fd, 0644) != 0 || ::fsync(fd) != 0) {
    throw fail("cannot flush the temporary file");
  }
  if (::close(fd) != 0) {
    const int error = errno;
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw write_error(path, "cannot close the temporary file", error);
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw std::runtime_error("cannot write " + path.string() + ": " + error.message());
  }
}

}  // namespace flowsteer::base
