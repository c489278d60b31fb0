#include "shape/core/atomic_file.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <system_error>

#include "shape/core/error.h"

namespace pectus {
namespace fs = std::filesystem;
namespace {

fs::path TempPathFor(const fs::path& target) {
  static std::atomic<unsigned> counter{0};
  const std::string name = "." + target.stem().string() + ".pectus-tmp-" + std::to_string(::getpid()) + "-" +
                           std::to_string(counter++) + target.extension().string();
  return target.parent_path() / name;
}

void EnsureParent(const fs::path& target) {
  const fs::path parent = target.parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) ThrowFailure("cannot create folder: " + ec.message(), parent.string());
}

void RenameInto(const fs::path& temp, const fs::path& target) {
  std::error_code ec;
  fs::rename(temp, target, ec);
  if (ec) {
    fs::remove(temp, ec);
    ThrowFailure("cannot move the finished file into place: " + ec.message(), target.string());
  }
}

}  // namespace

AtomicOutput::AtomicOutput(fs::path target) : target_(std::move(target)), buffer_(1 << 20) {
  EnsureParent(target_);
  temp_ = TempPathFor(target_);
  stream_.rdbuf()->pubsetbuf(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
  stream_.open(temp_, std::ios::binary | std::ios::trunc);
  if (!stream_) ThrowFailure("cannot open for writing", target_.string());
}

AtomicOutput::~AtomicOutput() {
  if (!committed_) {
    stream_.close();
    std::error_code ec;
    fs::remove(temp_, ec);
  }
}

void AtomicOutput::Commit() {
  stream_.flush();
  const bool ok = static_cast<bool>(stream_);
  stream_.close();
  if (!ok || stream_.fail()) ThrowFailure("write failed (disk full?)", target_.string());
  RenameInto(temp_, target_);
  committed_ = true;
}

void WriteFileAtomically(const fs::path& path, std::string_view contents) {
  AtomicOutput out(path);
  out.stream().write(contents.data(), static_cast<std::streamsize>(contents.size()));
  out.Commit();
}

OutputTransaction::~OutputTransaction() {
  for (const Entry& e : staged_) {
    if (e.move) continue;
    std::error_code ec;
    fs::remove_all(e.from, ec);
  }
}

fs::path OutputTransaction::Stage(const fs::path& target) {
  EnsureParent(target);
  fs::path temp = TempPathFor(target);
  staged_.push_back({temp, target, false});
  return temp;
}

void OutputTransaction::MoveAtCommit(const fs::path& from, const fs::path& target) {
  EnsureParent(target);
  staged_.push_back({from, target, true});
}

namespace {

// `from` onto `target` (a folder replaces a folder whole): a rename, or where the two are on different file
// systems a copy beside the target renamed into place, then `from` removed.
void MoveInto(const fs::path& from, const fs::path& target) {
  std::error_code ec;
  if (fs::is_directory(target, ec) && fs::is_directory(from, ec)) fs::remove_all(target, ec);
  fs::rename(from, target, ec);
  if (!ec) return;
  if (ec != std::errc::cross_device_link)
    ThrowFailure("cannot move a result into the outputs: " + ec.message(), target.string());
  ec.clear();
  const fs::path temp = TempPathFor(target);
  fs::copy(from, temp, fs::copy_options::recursive, ec);
  if (ec) {
    fs::remove_all(temp, ec);
    ThrowFailure("cannot copy a result into the outputs: " + ec.message(), target.string());
  }
  RenameInto(temp, target);
  fs::remove_all(from, ec);
}

}  // namespace

void OutputTransaction::CommitAll() {
  std::vector<Entry> pending;
  for (const Entry& e : staged_) {
    std::error_code ec;
    if (e.move) {
      if (fs::exists(e.from, ec)) MoveInto(e.from, e.target);
      continue;
    }
    if (fs::exists(e.from, ec)) {
      MoveInto(e.from, e.target);
    } else {
      pending.push_back(e);  // a stage not written yet: for a later commit
    }
  }
  staged_ = std::move(pending);
}

namespace {

// The device and inode of an existing file (links followed, as fs::equivalent does).
bool FileIdentity(const fs::path& path, std::pair<std::uint64_t, std::uint64_t>* id) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return false;
  *id = {static_cast<std::uint64_t>(st.st_dev), static_cast<std::uint64_t>(st.st_ino)};
  return true;
}

}  // namespace

void MoveFilesInto(const fs::path& from, const std::function<fs::path(const fs::path&)>& target) {
  std::error_code ec;
  if (!fs::is_directory(from, ec)) return;
  std::vector<fs::path> files;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(from)) {
    if (e.is_regular_file()) files.push_back(fs::relative(e.path(), from));
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& name : files) {
    const fs::path to = target(name);
    fs::rename(from / name, to, ec);
    if (ec) {
      ec.clear();
      fs::copy_file(from / name, to, fs::copy_options::overwrite_existing, ec);
      if (ec)
        ThrowFailure("cannot move a file of the work folder into the outputs: " + ec.message(), to.string());
    }
  }
}

void RefuseOverwritingInputs(const fs::path& output, const std::vector<fs::path>& inputs) {
  InputGuard(inputs).Refuse(output);
}

InputGuard::InputGuard(const std::vector<fs::path>& inputs) {
  for (const fs::path& in : inputs) {
    std::error_code ec;
    canonical_.insert(fs::weakly_canonical(in, ec).string());
    std::pair<std::uint64_t, std::uint64_t> id;
    if (FileIdentity(in, &id)) files_.insert(id);
  }
}

void InputGuard::RefuseFolder(const fs::path& folder) const {
  std::error_code ec;
  const std::string inside = fs::weakly_canonical(folder, ec).string() + '/';
  const auto first = canonical_.lower_bound(inside);
  if (first != canonical_.end() && first->compare(0, inside.size(), inside) == 0) {
    ThrowUsage("output folder " + folder.string() + " holds an input (" + *first +
               "); pectus never overwrites its input");
  }
  if (!fs::is_directory(folder, ec)) return;
  for (fs::recursive_directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    std::pair<std::uint64_t, std::uint64_t> id;
    if (FileIdentity(it->path(), &id) && files_.count(id) > 0) {
      ThrowUsage("output folder " + folder.string() + " holds an input (" + it->path().string() +
                 "); pectus never overwrites its input");
    }
  }
}

void InputGuard::Refuse(const fs::path& output) const {
  std::error_code ec;
  std::pair<std::uint64_t, std::uint64_t> id;
  if (canonical_.count(fs::weakly_canonical(output, ec).string()) > 0 ||
      (FileIdentity(output, &id) && files_.count(id) > 0)) {
    ThrowUsage("output " + output.string() + " is also an input; pectus never overwrites its input");
  }
}

}  // namespace pectus
