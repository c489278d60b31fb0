// A file for fuzz targets that read through a path: an anonymous in-memory file (memfd) reached through a
// symlink with the extension the reader dispatches on, made once per process. Each input replaces the
// file's bytes; nothing is written to disk.
#pragma once

#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace pectus::fuzz {

class FuzzFile {
 public:
  /// A file named fuzz<extension> (e.g. ".ply") in a private temporary folder.
  explicit FuzzFile(const std::string& extension) {
    fd_ = memfd_create("pectus-fuzz", 0);
    if (fd_ < 0) std::abort();
    char folder[] = "/tmp/pectus-fuzz-XXXXXX";
    if (mkdtemp(folder) == nullptr) std::abort();
    folder_ = folder;
    path_ = folder_ / ("fuzz" + extension);
    std::filesystem::create_symlink("/proc/" + std::to_string(getpid()) + "/fd/" + std::to_string(fd_),
                                    path_);
  }
  ~FuzzFile() {
    std::error_code ec;
    std::filesystem::remove_all(folder_, ec);
    close(fd_);
  }
  FuzzFile(const FuzzFile&) = delete;
  FuzzFile& operator=(const FuzzFile&) = delete;

  /// Replaces the file's contents with `size` bytes at `data`; returns its path.
  const std::filesystem::path& Write(const std::uint8_t* data, std::size_t size) {
    if (ftruncate(fd_, 0) != 0) std::abort();
    std::size_t done = 0;
    while (done < size) {
      const ssize_t n = pwrite(fd_, data + done, size - done, static_cast<off_t>(done));
      if (n <= 0) std::abort();
      done += static_cast<std::size_t>(n);
    }
    return path_;
  }

 private:
  int fd_ = -1;
  std::filesystem::path folder_, path_;
};

}  // namespace pectus::fuzz
