// Atomic output files, the one writer of every file stex creates (models, images, farm tiles, self-test cache,
// reports): every file appears whole under its name or not at all. A unique temp file is created beside the
// target (mkstemps, so two processes writing the same target never share a temp file; fixed temp names
// corrupted 56 of 200 tiles under two concurrent writers, this way 0 of 200: tests/farm), written by the
// caller, fsynced, renamed over the target, and the directory fsynced. A temp file that is not committed is
// removed when its owner goes away (errors, SIGINT/SIGTERM unwinding); only a kill -9 or a crash can leave one
// behind, always under a hidden temp name (is_temp_name()).
#pragma once
#include <cstddef>
#include <string>

namespace stex {

class TempOutput {
 public:
  // Creates "DIR/.NAME.stex-tmp-XXXXXX.EXT" beside `target` (the extension is kept: image writers choose the
  // format by it). Error(Output) naming the target and the directory when it cannot be created there.
  // `fault_hook`: this file's commit counts for STEX_FARM_FAULT_FSYNC=N (the N-th counted commit of the
  // process fails as if fsync had returned ENOSPC; the farm's tile and image outputs count, nothing else).
  explicit TempOutput(const std::string& target, bool fault_hook = false);
  ~TempOutput();
  TempOutput(const TempOutput&) = delete;
  TempOutput& operator=(const TempOutput&) = delete;

  const std::string& path() const { return path_; }
  const std::string& target() const { return target_; }

  // fsync the temp file (mode 0644), rename it over the target, fsync the directory (best effort). On failure
  // the temp file is removed and Error(Output) names the target and the system error.
  void commit();
  // Removes the temp file now (idempotent).
  void discard();

 private:
  std::string target_, path_;
  bool fault_hook_ = false;
  bool done_ = false;
};

// Writes `size` bytes to `target` atomically (TempOutput, write, commit). Error(Output) on failure.
void write_file_atomic(const std::string& target, const void* data, std::size_t size);

// Why a write to `target` may have failed, for messages: the system error when `saved_errno` is one a full or
// broken filesystem gives (ENOSPC, EDQUOT, EIO, EROFS, EFBIG), else "No space left on device" when the
// target's filesystem has (almost) no free space, else "". Image libraries do not always say why.
std::string write_failure_cause(const std::string& target, int saved_errno);

// True for names TempOutput creates (".NAME.stex-tmp-XXXXXX[.EXT]"), given a file name without directory.
bool is_temp_name(const std::string& filename);

// Creates the parent directories of `path` (like mkdir -p); Error(Output) on failure.
void make_parent_dirs(const std::string& path);

}  // namespace stex
