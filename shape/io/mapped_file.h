// pectus: read-only memory map of an input file.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace pectus {

/// A whole file mapped read-only into memory. Throws Error(kBadInput) naming the file if it does not
/// exist, is a folder or cannot be read. An empty file maps to an empty view.
class MappedFile {
 public:
  explicit MappedFile(const std::string& path);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  std::string_view bytes() const { return {data_, size_}; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  const char* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace pectus
