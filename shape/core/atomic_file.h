// pectus: outputs written atomically (temporary file in the same folder, then rename).
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace pectus {

/// Writes one file atomically: everything goes to a hidden temporary file beside the target, which
/// Commit() renames over the target. If the object is destroyed without Commit() (an exception, an
/// early return), the temporary file is removed and the target is untouched.
class AtomicOutput {
 public:
  explicit AtomicOutput(std::filesystem::path target);
  ~AtomicOutput();
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;

  /// Binary stream on the temporary file (1 MiB buffer).
  std::ofstream& stream() { return stream_; }
  /// Flushes, checks for write errors (Error(kFailure) naming the target), renames into place.
  void Commit();

 private:
  std::filesystem::path target_;
  std::filesystem::path temp_;
  std::vector<char> buffer_;
  std::ofstream stream_;
  bool committed_ = false;
};

/// Writes `contents` to `path` atomically.
void WriteFileAtomically(const std::filesystem::path& path, std::string_view contents);

/// A set of outputs of one command, committed together: Stage() hands out a temporary path beside each
/// target (same extension, so format detection still works); MoveAtCommit() names files or folders made
/// elsewhere (a work folder's); CommitAll() renames them all into place. Destroyed without CommitAll(), it
/// removes every staged file and leaves every file to move where it is, so a failed run leaves nothing
/// behind and loses nothing a rerun would need.
class OutputTransaction {
 public:
  OutputTransaction() = default;
  ~OutputTransaction();
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;

  /// A temporary path to write `target` to. Creates the target's parent folder if needed.
  std::filesystem::path Stage(const std::filesystem::path& target);
  /// Moves `from` (a file or a folder) onto `target` at CommitAll(): one rename (a copy where `from` is on
  /// another file system), replacing what is at `target` (a folder whole). Creates the target's parent
  /// folder now. Nothing happens to `from` until then.
  void MoveAtCommit(const std::filesystem::path& from, const std::filesystem::path& target);
  /// Renames every staged file that was written onto its target and makes every move, in the order they
  /// were staged; a stage not written yet stays staged for a later CommitAll() (a command may commit its
  /// outputs before the report of the run is written). Throws Error(kFailure) naming a target that cannot
  /// be put in place.
  void CommitAll();

 private:
  struct Entry {
    std::filesystem::path from, target;
    bool move = false;  // `from` is not ours: left in place if not committed
  };
  std::vector<Entry> staged_;
};

/// Moves every file under `from` (files made by a task in a work folder, at their paths relative to the
/// outputs) to where `target(relative path)` says, in path order: a rename, or a copy where the work folder
/// is on another file system. Nothing if `from` does not exist. Throws Error(kFailure) naming the file.
void MoveFilesInto(const std::filesystem::path& from,
                   const std::function<std::filesystem::path(const std::filesystem::path&)>& target);

/// Throws Error(kUsage) if `output` names the same file as any of `inputs` (pectus never overwrites
/// its input).
void RefuseOverwritingInputs(const std::filesystem::path& output,
                             const std::vector<std::filesystem::path>& inputs);

/// RefuseOverwritingInputs for many outputs against the same inputs: the inputs are resolved once (their
/// canonical paths and their files' device and inode), so that each output costs O(1) look-ups rather than
/// O(#inputs) (a cohort's thousands of outputs against its thousands of sweeps).
class InputGuard {
 public:
  explicit InputGuard(const std::vector<std::filesystem::path>& inputs);
  /// Throws Error(kUsage) if `output` is one of the inputs: the same canonical path, or the same file
  /// reached another way (a link).
  void Refuse(const std::filesystem::path& output) const;
  /// Refuse() for a folder that an output replaces whole: throws Error(kUsage) if an input lies under
  /// `folder`, by its path or as one of the files there now (O(log inputs) look-ups, and one per file of
  /// the folder if it exists).
  void RefuseFolder(const std::filesystem::path& folder) const;

 private:
  std::set<std::string> canonical_;                          // ordered: the inputs under a folder are a range
  std::set<std::pair<std::uint64_t, std::uint64_t>> files_;  // (device, inode) of each existing input
};

}  // namespace pectus
