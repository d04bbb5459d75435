#include "formats/durable_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

#include "rt/formatted.hpp"

namespace stac::formats {
namespace {

// Every byte to `fd` (retrying short writes and EINTR); false with errno set on a failure.
bool write_all(int fd, const void* data, std::size_t size) noexcept {
  const auto* p = static_cast<const char*>(data);
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd, p + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = EIO;
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  return true;
}

rt::Status sync_folder(const std::filesystem::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return rt::make_error(dir.string() + ": cannot open the folder to sync it");
  const int r = ::fsync(fd);
  ::close(fd);
  if (r != 0) return rt::make_error(dir.string() + ": fsync failed (" + std::strerror(errno) + ")");
  return {};
}

// A torn last line (no '\n' at the end): the file back to just after its last complete line.
rt::Status cut_tail(int fd, const std::filesystem::path& path) {
  off_t end = ::lseek(fd, 0, SEEK_END);
  char last = '\n';
  if (end > 0 && ::pread(fd, &last, 1, end - 1) == 1 && last != '\n') {
    char c = 0;
    while (end > 0 && ::pread(fd, &c, 1, end - 1) == 1 && c != '\n') --end;
    if (::ftruncate(fd, end) != 0 || ::fsync(fd) != 0)
      return rt::make_error(path.string() + ": cannot cut its torn last line (" +
                            std::strerror(errno) + ")");
  }
  return {};
}

}  // namespace

rt::Status write_file_durably(const std::filesystem::path& path,
                              std::span<const std::uint8_t> bytes) {
  std::filesystem::path tmp = path;
  tmp += ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0)
    return rt::make_error(tmp.string() + ": cannot create (" + std::strerror(errno) +
                          "); check the folder exists and is writable");
  if (!write_all(fd, bytes.data(), bytes.size())) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    ::unlink(tmp.c_str());
    return rt::make_error(path.string() + ": write failed (" + why + "); nothing was replaced");
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    ::unlink(tmp.c_str());
    return rt::make_error(path.string() + ": fsync failed; nothing was replaced");
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    return rt::make_error(path.string() + ": cannot replace (" + why + ")");
  }
  return sync_folder(path.has_parent_path() ? path.parent_path() : std::filesystem::path("."));
}

rt::Status cut_torn_tail(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return {};
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) return rt::make_error(path.string() + ": cannot open (" + std::strerror(errno) + ")");
  auto r = cut_tail(fd, path);
  ::close(fd);
  return r;
}

rt::Result<bool> complete_or_cut_tail(const std::filesystem::path& path,
                                      const std::function<bool(const std::string&)>& whole,
                                      const std::function<bool(const std::string&)>& complete) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return false;
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) return rt::make_error(path.string() + ": cannot open (" + std::strerror(errno) + ")");
  const off_t end = ::lseek(fd, 0, SEEK_END);
  off_t start = end;
  char c = '\n';
  while (start > 0 && ::pread(fd, &c, 1, start - 1) == 1 && c != '\n') --start;
  if (start == end) {  // empty, or ends with its newline
    ::close(fd);
    return false;
  }
  std::string last(static_cast<std::size_t>(end - start), '\0');
  if (::pread(fd, last.data(), last.size(), start) != static_cast<ssize_t>(last.size())) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    return rt::make_error(path.string() + ": cannot read its last line (" + why + ")");
  }
  if (whole(last)) {
    const bool ok = ::pwrite(fd, "\n", 1, end) == 1 && ::fsync(fd) == 0;
    const std::string why = ok ? "" : std::strerror(errno);
    ::close(fd);
    if (!ok) return rt::make_error(path.string() + ": cannot end its last line (" + why + ")");
    return false;
  }
  if (complete && complete(last)) {
    ::close(fd);
    std::ifstream in(path);
    const auto lines = static_cast<std::size_t>(
        std::count(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>(), '\n'));
    return rt::make_error(path.string() + ":" + std::to_string(lines + 1) +
                          ": the last line is complete but not a valid record (" +
                          rt::echoed(last) + "); fix or delete that line");
  }
  auto cut = cut_tail(fd, path);
  ::close(fd);
  if (!cut) return rt::make_error(cut.error().message);
  return true;
}

rt::Status write_text_durably(const std::filesystem::path& path, const std::string& text) {
  return write_file_durably(
      path, std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

rt::Status append_line_durably(const std::filesystem::path& path, const std::string& line) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0)
    return rt::make_error(path.string() + ": cannot open for appending (" + std::strerror(errno) +
                          ")");
  if (auto cut = cut_tail(fd, path); !cut) {
    ::close(fd);
    return cut;
  }
  const std::string text = line + "\n";
  if (!write_all(fd, text.data(), text.size())) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    return rt::make_error(path.string() + ": append failed (" + why + ")");
  }
  const bool synced = ::fsync(fd) == 0;
  ::close(fd);
  if (!synced) return rt::make_error(path.string() + ": fsync failed");
  return {};
}

}  // namespace stac::formats
